"""The emergency-stop experiments of [MLC] IV-C, each one command: `hrp2-console experiment NAME [--no-es]`.

Each runs in a fresh simulation as fast as possible, writes a CSV and a PNG shaped like Fig. 10 (CP
error, threshold, distance to the support-polygon edge, flag) and ends with a verdict line.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from controller.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    distance_to_polygon_edge,
    support_polygon,
)
from controller.system import ControllerSystem
from robot.generate import REACH_FORWARD_DEG
from robot.plant import MujocoPlant


@dataclass(frozen=True)
class ExperimentResult:
    name: str
    es: bool
    verdict: str  # "stood" | "fell"
    flag_time_s: float | None
    peak_cp_error_m: float
    cp_error_at_flag_m: float | None
    edge_margin_at_flag_m: float | None  # distance of the actual CP to the support edge when the flag rose
    below_threshold_after_revert_s: float | None  # time from the end of the revert to error < threshold
    duration_s: float
    csv_path: str | None
    png_path: str | None

    def verdict_line(self) -> str:
        flag = "none" if self.flag_time_s is None else f"{self.flag_time_s:.3f} s"
        return f"verdict: {self.verdict} (flag at {flag}, peak CP error {self.peak_cp_error_m * 1e3:.1f} mm)"


def _pose(system: ControllerSystem, changes_deg: dict[str, float]) -> np.ndarray:
    from robot.names import joint_index

    q = np.array(system.loop.snapshot.q_seq_rad, dtype=float)
    for name, deg in changes_deg.items():
        q[joint_index(name)] = math.radians(deg)
    return q


def _push_hands(system: ControllerSystem, limbs: tuple[str, ...], delta_world: np.ndarray, time_s: float) -> None:
    """setTargetPose: move each hand by `delta_world` [m] (hrpsys-style joint-space interpolation)."""
    loop = system.loop
    kin = system.kin
    ref = loop.snapshot.reference
    kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, loop.snapshot.q_seq_rad)
    from controller.rotations import matrix_to_rpy

    for limb in limbs:
        p, R = kin.frame_pose(f"{limb}_end")
        loop.call(lambda limb=limb, p=p, R=R: loop.chain["seq"].set_target_pose(
            limb, p + delta_world, matrix_to_rpy(R), time_s))


def wall_push_forward(system: ControllerSystem) -> list[tuple[float, Callable[[], None]]]:
    """Fig. 9 (alpha): both hands 0.25 m forward in 4 s, into the wall in front."""
    seq = system.loop.chain["seq"]
    return [
        (0.0, lambda: seq.set_joint_angles(_pose(system, REACH_FORWARD_DEG), 2.0)),
        (3.0, lambda: _push_hands(system, ("rarm", "larm"), np.array([0.25, 0.0, 0.0]), 4.0)),
    ]


@dataclass(frozen=True)
class Experiment:
    scene: str
    script: Callable[[ControllerSystem], list[tuple[float, Callable[[], None]]]]
    duration_s: float
    description: str


EXPERIMENTS: dict[str, Experiment] = {
    "wall-push-forward": Experiment("wall", wall_push_forward, 12.0, wall_push_forward.__doc__),
}


def run_experiment(name: str, es: bool = True, out_dir: Path | None = None, settle_s: float = 2.5,
                   plot: bool = True) -> ExperimentResult:
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment {name!r}; available: {', '.join(EXPERIMENTS)}")
    exp = EXPERIMENTS[name]
    system = ControllerSystem(MujocoPlant(exp.scene))
    loop = system.loop
    if not es:
        loop.chain["es"].enabled = False
    loop.run_for(settle_s)  # AutoBalancer and Stabilizer blended in
    t0 = loop.snapshot.time_s
    events = sorted(exp.script(system), key=lambda e: e[0])
    rows = []
    flag_time = None
    fell_at = None
    t2 = loop.chain["es"].params.t2_s
    while loop.snapshot.time_s - t0 < exp.duration_s:
        t_rel = loop.snapshot.time_s - t0
        while events and events[0][0] <= t_rel + 1e-9:
            loop.call(events.pop(0)[1])
        snap = loop.step()
        st = snap.layers["st"]
        gait = snap.reference.gait
        feet = [((p[0], p[1], math.atan2(R[1, 0], R[0, 0])), rect) for (p, R, rect) in (
            (gait.p_rsole_world, gait.R_rsole_world, HRP2_RIGHT_SOLE),
            (gait.p_lsole_world, gait.R_lsole_world, HRP2_LEFT_SOLE))]
        edge = float(distance_to_polygon_edge(np.asarray(st["cp_act"]), support_polygon(feet)))
        es_st = snap.layers["es"]
        if es_st.get("stopped") and flag_time is None and es_st.get("flag_time") is not None:
            flag_time = es_st["flag_time"] - t0
        if not es and st["emergency"] and flag_time is None:
            flag_time = snap.time_s - t0
        rows.append([snap.time_s - t0, *st["cp_error"], st["cp_error_norm"], st["threshold"], edge,
                     float(st["emergency"]), float(bool(es_st.get("stopped"))), float(snap.fallen)])
        if snap.fallen:
            fell_at = snap.time_s - t0
            break
    data = np.array(rows)
    t = data[:, 0]
    err = data[:, 3]
    threshold = float(data[0, 4])
    at_flag = edge_at_flag = recovered = None
    if flag_time is not None:
        k = int(np.searchsorted(t, flag_time))
        k = min(k, len(t) - 1)
        at_flag, edge_at_flag = float(err[k]), float(data[k, 5])
        after = np.flatnonzero((t >= flag_time + t2) & (err < threshold))
        if after.size:
            recovered = float(t[after[0]] - (flag_time + t2))
    result_name = f"{name}{'' if es else '-no-es'}"
    csv_path = png_path = None
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        csv_path = out_dir / f"{result_name}.csv"
        with open(csv_path, "w", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(["time_s", "cp_error_x_m", "cp_error_y_m", "cp_error_m", "threshold_m",
                        "cp_to_support_edge_m", "flag", "motion_stopped", "fallen"])
            w.writerows([[f"{v:.6g}" for v in r] for r in rows])
        if plot:
            png_path = out_dir / f"{result_name}.png"
            plot_fig10(data, flag_time, f"{name} ({'with' if es else 'without'} EmergencyStopper)", png_path)
    return ExperimentResult(
        name=name, es=es, verdict="fell" if fell_at is not None else "stood", flag_time_s=flag_time,
        peak_cp_error_m=float(err.max()), cp_error_at_flag_m=at_flag, edge_margin_at_flag_m=edge_at_flag,
        below_threshold_after_revert_s=recovered, duration_s=float(t[-1]),
        csv_path=None if csv_path is None else str(csv_path), png_path=None if png_path is None else str(png_path))


def plot_fig10(data: np.ndarray, flag_time: float | None, title: str, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = data[:, 0]
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, data[:, 3] * 1e3, color="tab:red", label="capture-point error")
    ax.plot(t, data[:, 4] * 1e3, color="tab:blue", label="threshold")
    ax.plot(t, (data[:, 3] + data[:, 5]) * 1e3, color="black", ls="--", lw=1,
            label="error at which the CP leaves the support polygon")
    top = max(data[:, 3].max(), data[:, 4].max()) * 1e3 * 1.2
    ax.fill_between(t, 0, data[:, 7] * top, color="tab:pink", alpha=0.3, label="motion stopped")
    if flag_time is not None:
        ax.axvline(flag_time, color="tab:pink", lw=1)
    ax.set_ylim(0, max(top, 1.0))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("[mm]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
