"""The push map's runs (issue 26): the robot walking (goVelocity) is pushed on BODY at a phase of its gait cycle,
with an impulse in a direction of its own frame, and watched; one run's spec, its key, and the run itself."""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

#: Bump when a change makes stored results stale (what a run does or what it reports).
STORE_FORMAT = 3
SETTLE_S = 2.5  # [s] standing before the walk
PUSH_S = 0.1  # [s] the push's duration: its force is impulse / PUSH_S
WARMUP_S = 2.0  # [s] phase 0 is the first right touchdown at least this long after goVelocity (a steady walk)
CYCLE_S = 2.0  # [s] the gait cycle (two 1.0 s steps, the AutoBalancer's goVelocity timing); measured in each run
WATCH_S = 6.0  # [s] after the push
PUSH_BODY = "BODY"

#: the walks: (forward speed [m/s], turning rate [rad/s])
WALKS: dict[str, tuple[float, float]] = {"0.1": (0.1, 0.0), "0.2": (0.2, 0.0), "turn": (0.1, math.radians(10.0))}


def walk_label(walk: str) -> str:
    vx, vtheta = WALKS[walk]
    return f"{vx:g} m/s" + (f", turning {math.degrees(vtheta):g} deg/s" if vtheta else "")


@dataclass(frozen=True)
class PushSpec:
    """One run: the walk (a key of WALKS), the impulse [N s], its direction in the robot's frame [deg] (0 forward,
    90 left), the phase of the gait cycle (0..1 from a right touchdown) and how long it is watched after the push."""

    walk: str
    impulse_ns: float
    direction_deg: float
    phase: float
    watch_s: float = WATCH_S

    def __post_init__(self) -> None:
        if self.walk not in WALKS:
            raise ValueError(f"unknown walk {self.walk!r}; choose from {', '.join(WALKS)}")
        if not (self.impulse_ns >= 0.0 and 0.0 <= self.phase < 1.0 and self.watch_s > 0.0):
            raise ValueError(f"impulse >= 0, phase in [0, 1) and watch > 0 expected, got {self}")

    def to_dict(self) -> dict[str, Any]:
        return {"format": STORE_FORMAT, "study": "push-walking", "walk": self.walk, "impulse_ns": self.impulse_ns,
                "direction_deg": self.direction_deg, "phase": self.phase, "watch_s": self.watch_s}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> PushSpec:
        return cls(d["walk"], float(d["impulse_ns"]), float(d["direction_deg"]), float(d["phase"]),
                   float(d["watch_s"]))

    def key(self) -> str:
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def expected_sim_s(self) -> float:
        """[s] simulated if no fall ends it early: for the progress bar's estimate."""
        return SETTLE_S + WARMUP_S + 1.0 + self.phase * CYCLE_S + PUSH_S + self.watch_s


def grid(walks, impulses_ns, directions: int, phases: int, watch_s: float = WATCH_S) -> list[PushSpec]:
    """Every walk x impulse x direction (`directions` evenly from forward, counter-clockwise) x phase (`phases`
    evenly over the cycle)."""
    return [PushSpec(w, float(j), 360.0 * d / directions, k / phases, watch_s) for w in walks for j in impulses_ns
            for d in range(directions) for k in range(phases)]


#: The result fields a run reports; the same run gives the same values wherever it runs.
RESULT_FIELDS = ("outcome", "fall_after_push_s", "peak_cp_error_m", "flag", "flag_after_push_s", "flag_rises",
                 "walking_stop", "emergency_steps", "support_at_push", "since_touchdown_s", "cycle_measured_s",
                 "push_time_s", "cp_push_rel_xy", "walk_end_after_push_s", "motion_stop", "walking_at_end",
                 "end_tilt_deg", "end_base_z_m", "error")


def _yaw(quat_wxyz) -> float:
    w, x, y, z = (float(v) for v in quat_wxyz)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _tilt_deg(quat_wxyz) -> float:
    """[deg] BODY's z axis from the vertical."""
    _, x, y, _ = (float(v) for v in quat_wxyz)
    return math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y)))))


def _cp_from_sole(obs, phase: float) -> list[float]:
    """The capture point the Stabilizer estimates at the push, from the sole the LIP's model places (the stance sole
    in single support, the one that landed last in double support: the right one in the first half of the cycle),
    in that sole's frame [m]: the walk's own state for the capturability (its model's nominal one has no sway)."""
    g = obs.snapshot.reference.gait  # the AutoBalancer's plan as published, in the controller's frame (as cp_act)
    right = g.support == "rleg" or (g.support == "both" and phase < 0.5)
    p, R = (g.p_rsole_world, g.R_rsole_world) if right else (g.p_lsole_world, g.R_lsole_world)
    yaw = math.atan2(float(R[1, 0]), float(R[0, 0]))
    dx, dy = (float(obs.layers["st"].cp_act[i]) - float(p[i]) for i in (0, 1))
    c, s_ = math.cos(yaw), math.sin(yaw)
    return [c * dx + s_ * dy, -s_ * dx + c * dy]  # a list: as it reads back from the store


def walk_to_phase(robot, vx_m_s: float, vy_m_s: float, vtheta_rad_s: float, phase: float
                  ) -> tuple[float | None, float]:
    """goVelocity, then step `robot` (a LocalRobot) to `phase` of the gait cycle: 0 is the first right touchdown
    (support lleg -> both on the AutoBalancer's status) at least WARMUP_S into the walk. Returns the cycle measured
    between the last two right touchdowns [s] (None with one) and when the support last changed [s]."""
    from app.service.verbs import GoVelocity

    robot.submit(GoVelocity(vx_m_s, vy_m_s, vtheta_rad_s)).result()
    t_walk = robot.host.observation.time_s
    prev, touchdowns, last_change = robot.host.observation.layers["abc"].support, [], t_walk
    while True:
        obs = robot.step()
        support = obs.layers["abc"].support
        if support != prev:
            last_change = obs.time_s
            if prev == "lleg" and support == "both":
                touchdowns.append(obs.time_s)
        prev = support
        if obs.fallen:
            raise RuntimeError(f"fell while walking before the push, at {obs.time_s:.2f} s")
        if touchdowns and touchdowns[-1] - t_walk >= WARMUP_S:
            break
        if obs.time_s - t_walk > WARMUP_S + 3 * CYCLE_S:
            raise RuntimeError(f"no right touchdown {WARMUP_S:g} s into the walk (support {support})")
    cycle = touchdowns[-1] - touchdowns[-2] if len(touchdowns) > 1 else None
    t_at = touchdowns[-1] + phase * CYCLE_S
    while robot.host.observation.time_s < t_at - 1e-9:
        obs = robot.step()
        support = obs.layers["abc"].support
        if support != prev:
            last_change = obs.time_s
        prev = support
    return cycle, last_change


def _push_run(s: PushSpec) -> tuple[dict[str, Any], float]:
    from app.service.local import LocalRobot
    from app.service.verbs import Push

    robot = LocalRobot("default")
    robot.run_for(SETTLE_S)
    vx, vtheta = WALKS[s.walk]
    cycle, last_change = walk_to_phase(robot, vx, 0.0, vtheta, s.phase)
    obs = robot.host.observation
    yaw = _yaw(obs.truth.base_quat_wxyz) + math.radians(s.direction_deg)
    force = s.impulse_ns / PUSH_S * np.array([math.cos(yaw), math.sin(yaw), 0.0])
    support_at_push, since = obs.layers["abc"].support, obs.time_s - last_change
    cp_rel = _cp_from_sole(obs, s.phase)
    t0 = obs.time_s
    robot.submit(Push(PUSH_BODY, tuple(float(f) for f in force), PUSH_S)).result()
    peak, flag_t, walking_stop, fall_t, steps, rises, was_up = 0.0, None, False, None, set(), 0, False
    walk_end_t, motion_stop = None, None
    for _ in range(int(round((PUSH_S + s.watch_s) / robot.loop.dt_control_s))):
        obs = robot.step()
        st, abc = obs.layers["st"], obs.layers["abc"]
        peak = max(peak, float(st.cp_error_norm))
        if st.emergency and flag_t is None:
            flag_t = obs.time_s - t0
        rises += bool(st.emergency and not was_up)
        was_up = bool(st.emergency)
        walking_stop = walking_stop or bool(abc.walking_stop)
        if walk_end_t is None and not abc.walking:
            walk_end_t = obs.time_s - t0
        if motion_stop is None and obs.layers["es"].stopped:
            motion_stop = obs.layers["es"].reason
        steps.update(r.time_s for r in abc.emergency_steps if r.time_s >= t0)
        if obs.fallen:
            fall_t = obs.time_s - t0
            break
    result = {"outcome": "fell" if fall_t is not None else "stood", "fall_after_push_s": fall_t,
              "peak_cp_error_m": peak, "flag": flag_t is not None, "flag_after_push_s": flag_t, "flag_rises": rises,
              "walking_stop": walking_stop, "emergency_steps": len(steps), "support_at_push": support_at_push,
              "since_touchdown_s": since, "cycle_measured_s": cycle, "push_time_s": t0,
              "cp_push_rel_xy": cp_rel, "walk_end_after_push_s": walk_end_t, "motion_stop": motion_stop,
              "walking_at_end": bool(obs.layers["abc"].walking), "end_tilt_deg": _tilt_deg(obs.truth.base_quat_wxyz),
              "end_base_z_m": float(obs.truth.base_pos_world[2]),
              "error": None}
    return result, obs.time_s


def run_push(spec: dict[str, Any]) -> dict[str, Any]:
    """Run `spec` (PushSpec.to_dict()) in a fresh simulation: {"key", "result", "timing"} (run.run_timed)."""
    from app.lab.study.run import run_timed

    return run_timed(PushSpec.from_dict(spec), _push_run, RESULT_FIELDS)
