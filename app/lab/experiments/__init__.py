"""The emergency-stop experiments of [MLC] IV-C, each one command: `hrp2-console experiment NAME [--no-es]`.

Each runs in a fresh simulation as fast as possible, writes a CSV and a PNG shaped like Fig. 10 (CP
error, threshold, distance to the support-polygon edge, flag) and ends with a verdict line. The motion
scripts are one module per scene (`wall.py`, ...); this module runs them and measures the outcome.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from app.lab.experiments import door, valve, wall
from app.lab.experiments.common import Experiment, ExperimentResult, Rig
from app.lab.experiments.fig10 import plot_fig10
from app.service import OperatorService, Refused
from app.service.local import LocalRobot
from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE, distance_to_polygon_edge, support_polygon

__all__ = ["EXPERIMENTS", "Experiment", "ExperimentResult", "run_experiment"]

#: Experiments by name (the CLI and the HTTP API list these).
EXPERIMENTS: dict[str, Experiment] = {**wall.EXPERIMENTS, **door.EXPERIMENTS, **valve.EXPERIMENTS}

CSV_COLUMNS = ("time_s", "cp_error_x_m", "cp_error_y_m", "cp_error_m", "threshold_m", "cp_to_support_edge_m",
               "flag", "motion_stopped", "fallen")


@lru_cache(maxsize=8)
def _support_polygon(feet: tuple) -> np.ndarray:
    return support_polygon([(pose, rect) for pose, rect in zip(feet, (HRP2_RIGHT_SOLE, HRP2_LEFT_SOLE), strict=True)])


def _edge_distance(snap) -> float:
    """Signed distance [m] of the actual capture point to the edge of the planned support polygon."""
    gait = snap.reference.gait
    feet = tuple((float(p[0]), float(p[1]), math.atan2(R[1, 0], R[0, 0])) for p, R in (
        (gait.p_rsole_world, gait.R_rsole_world), (gait.p_lsole_world, gait.R_lsole_world)))
    return float(distance_to_polygon_edge(np.asarray(snap.layers["st"].cp_act), _support_polygon(feet)))


def settled_below_after_s(t: np.ndarray, err: np.ndarray, threshold: float, t_from: float) -> float | None:
    """Time [s] from `t_from` until the error goes below `threshold` for good (to the end of the run);
    0 if it never exceeds it after `t_from`, None if it ends above it."""
    after = t >= t_from
    above = np.flatnonzero(after & (err >= threshold))
    if above.size == 0:
        return 0.0
    if above[-1] + 1 >= len(t):
        return None
    return float(t[above[-1] + 1] - t_from)


def run_experiment(name: str, es: bool = True, out_dir: Path | None = None, settle_s: float = 2.5,
                   plot: bool = True, variant: str | None = None, write_csv: bool = True,
                   params: Mapping[str, Mapping[str, Any]] | None = None,
                   duration_s: float | None = None,
                   disturbance: Mapping[str, float] | None = None) -> ExperimentResult:
    """Run experiment `name` (variant `variant`, default its first) with or without the EmergencyStopper.

    `params` changes layer parameters before the start, e.g. {"es": {"t1_s": 0.5}, "st": {"cp_threshold_m": 0.03}};
    `duration_s` ends the script early (default: the experiment's duration); `disturbance` sets some of the
    experiment's declared disturbances (`EXPERIMENTS[name].disturbances`; the others keep their defaults).
    """
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment {name!r}; available: {', '.join(EXPERIMENTS)}")
    exp = EXPERIMENTS[name]
    variant = exp.variants[0] if variant is None else variant
    if variant not in exp.variants:
        raise ValueError(f"unknown variant {variant!r} of {name}; available: {', '.join(exp.variants)}")
    disturbed = exp.disturbance(disturbance)
    robot = LocalRobot(exp.scene, speed=None)
    service = OperatorService(robot)
    rig = Rig(service, robot)
    loop = robot.loop
    if params:
        service.set_params(params)
    if not es:
        service.enable_layers({"es": False})
    if exp.place is not None:
        exp.place(rig, disturbed)
    wall_t0 = time.perf_counter()
    loop.run_for(settle_s)  # AutoBalancer and Stabilizer blended in
    for limb in exp.impedance:
        service.start_impedance(limb)
    t0 = loop.snapshot.time_s
    events = sorted(exp.script(rig, variant, disturbed), key=lambda e: e[0])
    rows = []
    flag_time = None
    fell_at = None
    refused: list[str] = []
    t2 = service.params("es")["es"].t2_s
    end_s = exp.duration_s if duration_s is None else min(exp.duration_s, duration_s)
    while loop.snapshot.time_s - t0 < end_s:
        t_rel = loop.snapshot.time_s - t0
        while events and events[0][0] <= t_rel + 1e-9:
            try:
                events.pop(0)[1]()  # the planner's verbs, between two ticks
            except Refused as exc:  # e.g. the motion stopped by the flag: the plan's next step does not run
                refused.append(f"{t_rel:.2f} s: {exc}")
        snap = robot.step()  # the snapshot, and the simulation's verdict beside it
        st = snap.layers["st"]
        es_st = snap.layers["es"]
        if es_st.stopped and flag_time is None and es_st.flag_time is not None:
            flag_time = es_st.flag_time - t0
        if not es and st.emergency and flag_time is None:
            flag_time = snap.time_s - t0
        rows.append([snap.time_s - t0, *st.cp_error, st.cp_error_norm, st.cp_threshold_m, _edge_distance(snap),
                     float(st.emergency), float(es_st.stopped), float(snap.fallen)])
        if snap.fallen:
            fell_at = snap.time_s - t0
            break
    sim_wall_s = time.perf_counter() - wall_t0  # simulating only: no set-up, no files, no plot
    outcome = exp.outcome(rig) if exp.outcome is not None else {}
    data = np.array(rows)
    t = data[:, 0]
    err = data[:, 3]
    threshold = float(data[0, 4])
    at_flag = edge_at_flag = recovered = None
    if flag_time is not None:
        k = min(int(np.searchsorted(t, flag_time)), len(t) - 1)
        at_flag, edge_at_flag = float(err[k]), float(data[k, 5])
        recovered = settled_below_after_s(t, err, threshold, flag_time + t2)
    label = name if variant == "default" else f"{name}-{variant}"
    result_name = f"{label}{'' if es else '-no-es'}"
    csv_path = png_path = None
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        if write_csv:
            csv_path = out_dir / f"{result_name}.csv"
            with open(csv_path, "w", newline="") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(CSV_COLUMNS)
                w.writerows([[f"{v:.6g}" for v in r] for r in rows])
        if plot:
            png_path = out_dir / f"{result_name}.png"
            plot_fig10(data, flag_time, f"{label} ({'with' if es else 'without'} EmergencyStopper)", png_path)
    return ExperimentResult(
        name=name, variant=variant, es=es, verdict="fell" if fell_at is not None else "stood",
        flag_time_s=flag_time, peak_cp_error_m=float(err.max()), cp_error_at_flag_m=at_flag,
        edge_margin_at_flag_m=edge_at_flag, min_edge_margin_m=float(data[:, 5].min()),
        below_threshold_after_revert_s=recovered, duration_s=float(t[-1]), outcome=outcome, refused=tuple(refused),
        faults=tuple(robot.host.stats.summary()["faults"]),
        emergency_steps=len(snap.layers["abc"].emergency_steps),
        real_time_factor=(settle_s + float(t[-1])) / sim_wall_s,
        csv_path=None if csv_path is None else str(csv_path), png_path=None if png_path is None else str(png_path))
