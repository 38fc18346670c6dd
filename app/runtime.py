"""The console's long-lived objects: the MuJoCo plant, the controller system and the data logger."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from controller.data_logger import DataLogger
from controller.rotations import matrix_to_rpy, quat_wxyz_to_matrix
from controller.system import ControllerSystem
from robot.names import JOINT_NAMES
from robot.plant import MujocoPlant, available_scenes


def jsonable(value: Any) -> Any:
    """Numpy arrays and scalars to lists and floats; NaN and infinities to None."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        f = float(value)
        return f if math.isfinite(f) else None
    if value is None or isinstance(value, str):
        return value
    return str(value)


def _opt_float(v: Any) -> float | None:
    return None if v is None else float(v)


def _xy(v: Any) -> list[float]:
    a = np.zeros(2) if v is None else np.asarray(v, dtype=float).reshape(-1)[:2]
    return [round(float(c), 6) for c in a]


def capture_point_state(st: dict[str, Any]) -> dict[str, Any]:
    """The Stabilizer's capture point (ref, act, error [m], |error| [m], threshold [m]) from its status;
    zeros when the layer is absent."""
    return {"ref": _xy(st.get("cp_ref")), "act": _xy(st.get("cp_act")), "error": _xy(st.get("cp_error")),
            "error_norm": round(float(st.get("cp_error_norm", 0.0)), 6),
            "threshold": float(st.get("threshold", 0.0))}


def emergency_state(loop_emergency: dict[str, Any], fault: str | None, es: dict[str, Any], abc: dict[str, Any],
                    st: dict[str, Any]) -> dict[str, Any]:
    """The `emergency` block of /api/state from the layers' status: the hard e-stop and the fault; the
    Stabilizer's capture-point flag and when it last rose (simulated time [s]); the EmergencyStopper's
    motion stop (why, since when); the AutoBalancer's emergency walking stop; the Stabilizer stopped by the
    operator. A layer that is absent counts as not stopped."""
    flag_rose_at = _opt_float(st.get("flag_rise_time"))
    return {"hard_stop": bool(loop_emergency.get("hard_stop", False)), "fault": fault,
            "flag": bool(st.get("emergency", False)),
            "flag_rise_time": flag_rose_at,  # older name of flag_rose_at
            "flag_rose_at": flag_rose_at,
            "motion_stop": bool(es.get("stopped", False)),
            "motion_stop_reason": es.get("reason"),
            "motion_stop_time": _opt_float(es.get("flag_time")),
            "walking_stop": bool(abc.get("walking_stop", False)),
            "stabilizer_stop": bool(st) and not st.get("active", True)}


def _deg(a) -> list[float]:
    return [round(float(v), 4) for v in np.rad2deg(np.asarray(a, dtype=float))]


class RunStats:
    """Counters kept over a whole run (updated in the loop thread, read after it stops)."""

    def __init__(self) -> None:
        self.ticks = 0
        self.max_loop_ms = 0.0  # [ms] whole tick, chain + physics
        self.fallen = False
        self.faults: set[str] = set()

    def update(self, snap) -> None:
        self.ticks += 1
        if snap.loop_ms > self.max_loop_ms:
            self.max_loop_ms = float(snap.loop_ms)
        if snap.fallen:
            self.fallen = True
        if snap.fault:
            self.faults.add(snap.fault)


class Runtime:
    """Owns the simulation and the control loop; everything else reads snapshots or sends commands.

    Commands go only through `call(fn)`, which runs `fn` inside the loop at a tick boundary (or at
    once, between ticks, when the loop thread is not running). Readers only read `loop.snapshot`.
    """

    def __init__(self, scene: str = "default", dt_control_s: float = 0.005, speed: float | None = 1.0,
                 log_length: int = 12000) -> None:
        self.scene = scene
        self.speed = speed
        self.logger = DataLogger(log_length)
        self.stats = RunStats()
        self.system = ControllerSystem(MujocoPlant(scene), dt_control_s=dt_control_s,
                                       on_snapshot=self._on_snapshot)
        # joint limits in JOINT_NAMES order [rad], from the controller's kinematic model
        self.q_lower_rad = np.array(self.system.kin.q_lower, dtype=float)
        self.q_upper_rad = np.array(self.system.kin.q_upper, dtype=float)
        self._reset_lock = threading.Lock()

    def __repr__(self) -> str:
        return f"Runtime(scene={self.scene!r}, speed={self.speed}, running={self.loop.running})"

    def _on_snapshot(self, snap) -> None:
        self.logger.record(snap)
        self.stats.update(snap)

    @property
    def loop(self):
        return self.system.loop

    # ---- lifecycle ----------------------------------------------------------------------------
    def start(self) -> None:
        self.loop.start(self.speed)

    def stop(self) -> None:
        self.loop.stop()

    @property
    def running(self) -> bool:
        return self.loop.running

    def call(self, fn: Callable[[], Any], timeout_s: float = 5.0) -> Any:
        """Run `fn` inside the loop at a tick boundary; return its result or re-raise its exception."""
        return self.loop.call(fn, timeout_s=timeout_s)

    def reset(self, scene: str | None = None) -> None:
        """Restart the simulation (optionally in another scene); the chain is rebuilt from scratch."""
        scene = self.scene if scene is None else scene
        with self._reset_lock:
            plant = MujocoPlant(scene)  # built outside the loop: the loop keeps ticking meanwhile
            loop = self.loop
            self.call(lambda: loop.replace_plant(plant), timeout_s=10.0)
            self.scene = scene
            self.logger.clear()

    # ---- read-only views --------------------------------------------------------------------
    @staticmethod
    def available_scenes() -> list[str]:
        return list(available_scenes())

    def body_names(self) -> list[str]:
        """The MuJoCo bodies that can be pushed (the world body excluded)."""
        m = self.loop.plant.model
        return [m.body(i).name for i in range(1, m.nbody)]

    def joint_limits_deg(self, name: str) -> tuple[float, float]:
        i = JOINT_NAMES.index(name)
        return float(np.rad2deg(self.q_lower_rad[i])), float(np.rad2deg(self.q_upper_rad[i]))

    def state(self) -> dict[str, Any]:
        """The latest snapshot as a JSON-able dict (the GET /api/state contract)."""
        snap = self.loop.snapshot
        truth = snap.truth
        rpy_truth = matrix_to_rpy(quat_wxyz_to_matrix(np.asarray(truth.base_quat_wxyz, dtype=float)))
        cmd, meas, seq = (_deg(snap.q_cmd_rad), _deg(snap.q_meas_rad), _deg(snap.q_seq_rad))
        joints = {n: {"cmd_deg": cmd[i], "meas_deg": meas[i], "seq_deg": seq[i]}
                  for i, n in enumerate(JOINT_NAMES)}
        abc = snap.layers.get("abc") or {}
        st = snap.layers.get("st") or {}
        es = snap.layers.get("es") or {}
        return jsonable({
            "time": round(float(snap.time_s), 6),
            "tick": int(snap.tick),
            "fallen": bool(snap.fallen),
            "base": {"pos": np.asarray(truth.base_pos_world).round(5), "rpy_deg": _deg(rpy_truth),
                     "linvel": np.asarray(truth.base_linvel_world).round(5), "source": "simulation"},
            "estimate": {"rpy_deg": _deg(snap.base_rpy_est_rad), "source": "kf"},
            "joints": joints,
            "cog": np.asarray(snap.cog_world).round(5),
            "zmp": np.asarray(snap.zmp_world).round(5),
            "walking": bool(abc.get("walking", False)),
            "support": str(abc.get("support", "both")),
            "capture_point": capture_point_state(st),
            "emergency": emergency_state(snap.emergency, snap.fault, es, abc, st),
            "layers": snap.layers,
            "chain": self.loop.chain.describe(),
            "speed": self.speed,
            "scene": self.scene,
            "loop_ms": round(float(snap.loop_ms), 4),
        })
