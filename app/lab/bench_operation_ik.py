"""The operation IK's benchmark: the placo solve per scenario (idle, hands and head, stepping) timed on this machine."""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from controller.kinematics.operation_ik import (
    FOOT_FRAMES,
    HAND_FRAMES,
    FeetPoses,
    GazeTarget,
    HandTarget,
    OperationIK,
    OperationTargets,
)
from robot.names import PARAMETERS_JSON


def _half_sitting() -> tuple[np.ndarray, np.ndarray]:
    """HRP-2's half-sitting joint angles (30,) [rad] and BODY position (3,) [m] (robot/data parameters)."""
    hs = json.loads(PARAMETERS_JSON.read_text())["half_sitting_deg"]
    deg = [*hs["RLEG"], *hs["LLEG"], *hs["CHEST"], *hs["HEAD"], *hs["RARM"], *hs["LARM"]]
    return np.deg2rad(deg), np.array((0.0, 0.0, hs["base_height_m"]))


def _scenario_targets(name: str, ticks: int, q: np.ndarray, base: np.ndarray) -> list:
    """(targets, feet, COM x-y) per tick: idle; both hands on 5 cm circles, gaze sweeping; the same while
    stepping in place: every 0.8 s, 0.2 s of double support moving the COM over the next stance sole, then
    the other sole lifts 4 cm and swings 3 cm forward and back (a COM plan as the AutoBalancer would give;
    the hands go along with it)."""
    ik = OperationIK()
    ik.robot.state.q = ik.to_placo(q, base, np.eye(3))
    ik.robot.update_kinematics()
    T = {f: ik.robot.get_T_world_frame(f) for f in (*HAND_FRAMES.values(), *FOOT_FRAMES)}
    com0 = ik.robot.com_world()[:2]
    ankles = [T[f][:2, 3] + (0.015, 0.0) for f in FOOT_FRAMES]  # (x, y) over each sole's middle
    out = []
    for k in range(ticks):
        t = k * ik.params.dt_s
        if name == "idle":
            out.append((OperationTargets(), None, None))
            continue
        c = 0.05 * np.array((math.cos(2.0 * t) - 1.0, 0.0, math.sin(2.0 * t)))
        feet = com = None
        if name == "walking":
            phase, step = math.modf(t / 0.8)
            swing = int(step) % 2  # 0: the right sole swings (the left carries), 1: the left
            stance_before = com0 if step == 0 else ankles[swing]
            p = [T[f][:3, 3].copy() for f in FOOT_FRAMES]
            if phase < 0.25:  # double support: the COM goes over the next stance sole
                s = 0.5 * (1.0 - math.cos(math.pi * phase / 0.25))
                com = (1.0 - s) * stance_before + s * ankles[1 - swing]
                contact = (True, True)
            else:
                a = math.sin(math.pi * (phase - 0.25) / 0.75)
                p[swing] = p[swing] + (0.03 * a, 0.0, 0.04 * a)
                com = ankles[1 - swing]
                contact = (swing == 1, swing == 0)
            feet = FeetPoses(p[0], T[FOOT_FRAMES[0]][:3, :3], p[1], T[FOOT_FRAMES[1]][:3, :3], contact)
            c = c + (com[0] - com0[0], com[1] - com0[1], 0.0)  # the hands go along with the body
        targets = OperationTargets(
            rhand=HandTarget(T["rarm_end"][:3, 3] + (0.1, 0.0, 0.1) + c, T["rarm_end"][:3, :3]),
            lhand=HandTarget(T["larm_end"][:3, 3] + (0.1, 0.0, 0.1) + c * (1.0, 1.0, -1.0), T["larm_end"][:3, :3]),
            head=GazeTarget(yaw_rad=0.4 * math.sin(t), pitch_rad=0.2 + 0.1 * math.sin(3.0 * t)))
        out.append((targets, feet, com))
    return out


def benchmark(ticks: int = 3000, warmup: int = 300) -> dict[str, dict[str, float]]:
    """Per-solve time [ms] (median, p99, max) of each scenario, and of placo's solve alone, on this machine;
    the AutoBalancer's closed-form whole-body IK (controller/kinematics/fullbody_ik.py) for comparison."""
    from controller.kinematics.fullbody_ik import FullbodyIK  # only for the comparison
    from controller.kinematics.model import RobotKinematics

    q, base = _half_sitting()
    rpy = np.zeros(3)
    out = {}
    for name in ("idle", "hands+head", "walking"):
        ik = OperationIK()
        plan = _scenario_targets(name, warmup + ticks, q, base)
        qp_times: list[float] = []
        solve = ik.solver.solve

        def timed_solve(apply, solve=solve, qp_times=qp_times):
            t0 = time.perf_counter()
            x = solve(apply)
            qp_times.append(time.perf_counter() - t0)
            return x

        times, ok = [], True
        for k, (targets, feet, com) in enumerate(plan):
            if k == warmup:
                ik.solver = _TimedSolver(ik.solver, timed_solve)
            t0 = time.perf_counter()
            res = ik.solve(q, base, rpy, targets, feet, com)
            dt = time.perf_counter() - t0
            ok &= res.ok
            if k >= warmup:
                times.append(dt)
        ik.solver = ik.solver.inner if isinstance(ik.solver, _TimedSolver) else ik.solver
        out[name] = {**_stats(times), "ok": ok}
        if qp_times:
            out[name]["placo_solve"] = _stats(qp_times)
    kin = RobotKinematics()
    kin.update_rpy(base, rpy, q)
    soles = kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")
    fb = FullbodyIK(RobotKinematics())
    times = []
    for k in range(warmup + ticks):
        t0 = time.perf_counter()
        fb.solve(q, float(base[2]), np.eye(3), np.array((0.0, 0.02 * math.sin(0.01 * k))), *soles)
        if k >= warmup:
            times.append(time.perf_counter() - t0)
    out["fullbody_ik (AutoBalancer, closed form)"] = _stats(times)
    return out


class _TimedSolver:
    """The placo solver with its solve() timed (benchmark only)."""

    def __init__(self, inner, solve) -> None:
        self.inner, self.solve = inner, solve

    def __getattr__(self, name):
        return getattr(self.inner, name)


def _stats(seconds: list[float]) -> dict[str, float]:
    ms = np.array(seconds) * 1e3
    return {"median_ms": float(np.median(ms)), "p99_ms": float(np.percentile(ms, 99)), "max_ms": float(ms.max())}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m app.lab.bench_operation_ik", description=__doc__)
    parser.add_argument("--ticks", type=int, default=3000, help="timed ticks per scenario (default 3000)")
    args = parser.parse_args(argv)
    for name, s in benchmark(args.ticks).items():
        line = f"{name:42s} median {s['median_ms']:.4f} ms  p99 {s['p99_ms']:.4f} ms  max {s['max_ms']:.3f} ms"
        if "placo_solve" in s:
            qp = s["placo_solve"]
            line += f"   (placo solve: median {qp['median_ms']:.4f} ms, p99 {qp['p99_ms']:.4f} ms)"
        if s.get("ok") is False:
            line += "   QP FAILED on some tick"
        print(line)


if __name__ == "__main__":
    main()
