"""The EXPO 2005 task of [OP] VI as an experiment: `hrp2-console experiment expo --can U V` (one trial) or
`--trials N --seed S` (random placements, a CSV and a summary table; the last line `N/M succeeded`).

A trial places the table, the trash box (at the same place relative to the table) and the can (simulator
operations the robot learns of only through its cameras), then runs the behaviours `locate_can -> take_can ->
locate_trash_box -> throw_can` through the operator service, as fast as possible. The operator says where
to look (the table's and the box's places, [OP] II). The simulator's poses only measure the errors: the can
as located vs where it is, the can at the release vs the hole's centre, whether the can ends inside the box."""

from __future__ import annotations

import csv
import functools
import multiprocessing
import time
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

import robot.generate as gen
from app.service import OperatorService
from app.service.local import LocalRobot

SETTLE_S = 2.5  # [s] standing before the first behaviour (the AutoBalancer starts in 2 s)
ROBOT_DISTANCE_RANGE_M = (1.5, 2.5)  # [m] robot (feet centre) to the table's near edge
CAN_FROM_EDGE_RANGE_M = gen.EXPO_CAN_FROM_EDGE_RANGE_M  # (0.10, 0.30) [m] inward from the near edge
CAN_ALONG_RANGE_M = (-0.60, 0.60)  # [m] along the near long side from its middle (the table is 1.5 m long)
RUN_TIMEOUT_S = 120.0  # [s] of simulated time per behaviour
CSV_COLUMNS = ("trial", "can_u_m", "can_v_m", "robot_distance_m", "verdict", "can_location_error_mm",
               "can_relocation_error_mm", "release_error_mm", "release_error_estimate_mm", "in_box", "fallen",
               "sim_time_s", "wall_time_s", "message")


@dataclass
class TrialResult:
    trial: int
    can_u_m: float
    can_v_m: float
    robot_distance_m: float
    verdict: str  # "succeeded" or "failed: why"
    can_location_error_mm: float | None  # the first locate_can, in the world (the robot has not walked yet)
    can_relocation_error_mm: float | None  # take_can's locate from near, in the world (odometry error included)
    release_error_mm: float | None  # the can's centre at the release vs the hole's centre, horizontal
    release_error_estimate_mm: float | None  # what the robot thinks it was (its own report)
    in_box: bool
    fallen: bool
    sim_time_s: float
    wall_time_s: float
    message: str
    landing_verdict: str | None = None  # where throw_can saw the can end, from its images ("in the box", ...)

    @property
    def succeeded(self) -> bool:
        return self.verdict == "succeeded"


def _hole_true_m(box_xy) -> np.ndarray:
    return np.array([box_xy[0], box_xy[1], gen.TRASH_BOX_OUTER_M[2]])


def inside_box(can_m: np.ndarray, box_xy) -> bool:
    """An object's centre (the can's, the trash's) inside the box's walls and below its lid (box yaw 0)."""
    lx, ly, height = gen.TRASH_BOX_OUTER_M
    t = gen.TRASH_BOX_WALL_M
    return (abs(can_m[0] - box_xy[0]) < lx / 2 - t and abs(can_m[1] - box_xy[1]) < ly / 2 - t
            and can_m[2] < height - t)


def run_trial(can_u_m: float, can_v_m: float, robot_distance_m: float = 2.0, trial: int = 0,
              progress=None, look_after: bool = True) -> TrialResult:
    """One trial: the can U along the near long side from its middle, V inward from the near edge [m]; the
    table's near edge `robot_distance_m` ahead of the robot, the trash box where it is relative to the table;
    `look_after`: throw_can ends by looking where the can landed (its verdict in `landing_verdict`)."""
    wall0 = time.perf_counter()
    robot = LocalRobot("expo", speed=None)
    service = OperatorService(robot)
    plant = robot.plant
    shift = robot_distance_m - gen.EXPO_TABLE_NEAR_EDGE_X_M
    edge_x = gen.EXPO_TABLE_NEAR_EDGE_X_M + shift
    plant.place_object("table", (edge_x + gen.EXPO_TABLE_SIZE_M[0] / 2, gen.EXPO_TABLE_CENTRE_Y_M))
    box_xy = (gen.TRASH_BOX_CENTRE_M[0] + shift, gen.TRASH_BOX_CENTRE_M[1])
    plant.place_object("trash_box", box_xy)
    can_true = plant.place_object("can", (edge_x + can_v_m, gen.EXPO_TABLE_CENTRE_Y_M + can_u_m))
    robot.run_for(SETTLE_S)
    hole = _hole_true_m(box_xy)
    look_table = {"x_m": edge_x + 0.15, "y_m": 0.0, "z_m": gen.EXPO_TABLE_SIZE_M[2] + 0.05}
    look_box = {"x_m": box_xy[0], "y_m": box_xy[1], "z_m": gen.TRASH_BOX_OUTER_M[2]}
    # the table's place is known ([OP] VI): take_can keeps the feet clear of its near edge
    steps = [("locate_can", look_table), ("take_can", {"table_edge_x_m": edge_x}), ("locate_trash_box", look_box),
             ("throw_can", {"look_after": look_after})]
    errors: dict[str, float | None] = {"locate": None, "relocate": None, "release": None, "estimate": None}
    landing = None
    message, fallen = "", False
    seen_relocate = False
    for name, params in steps:
        run_id = service.run_behavior(name, params)
        status = None
        for _ in range(int(RUN_TIMEOUT_S / robot.loop.dt_control_s)):
            obs = robot.step()
            status = service.get_run(run_id)
            phase = status.result.get("phase")
            if name == "take_can" and phase in ("walk", "open") and seen_relocate is False and \
                    status.result.get("steps") and any(s["behavior"] == "locate_can" for s in status.result["steps"]):
                seen_relocate = True
                rec = robot.host.recognitions.get("can")
                if rec is not None:
                    errors["relocate"] = 1e3 * float(np.linalg.norm(np.array(rec["position_m"]) - can_true))
            if name == "throw_can" and phase == "release" and errors["release"] is None:
                can_now = plant.object_pose("can")[0]
                errors["release"] = 1e3 * float(np.linalg.norm(can_now[:2] - hole[:2]))
            if obs.fallen:
                fallen = True
                break
            if status.state != "running":
                break
        if progress is not None:
            progress(f"  {name}: {status.state if status else '?'} ({status.message if status else ''})")
        if name == "locate_can" and status.state == "succeeded":
            rec = robot.host.recognitions["can"]
            errors["locate"] = 1e3 * float(np.linalg.norm(np.array(rec["position_m"]) - can_true))
        if name == "throw_can" and "release_estimate" in status.result:
            errors["estimate"] = 1e3 * status.result["release_estimate"]["error_m"]
        if name == "throw_can":
            landing = (status.result.get("landing") or {}).get("verdict")
        if fallen or status.state != "succeeded":
            message = "the robot fell" if fallen else f"{name} {status.state}: {status.message}"
            break
    robot.run_for(1.5)  # the can falls and comes to rest
    can_end = plant.object_pose("can")[0]
    in_box = inside_box(can_end, box_xy) and not fallen
    if not message and not in_box:
        message = f"the can ended outside the box, at ({can_end[0]:.3f}, {can_end[1]:.3f}, {can_end[2]:.3f}) m"
    sim_s = float(robot.loop.snapshot.time_s)
    robot.close()

    def fmt(v):
        return "-" if v is None else f"{v:.1f} mm"

    detail = (f"can location error {fmt(errors['locate'])}, release error {fmt(errors['release'])} "
              f"from the hole centre")
    verdict = "succeeded" if in_box and not message else f"failed: {message}"
    return TrialResult(trial, can_u_m, can_v_m, robot_distance_m, verdict, errors["locate"], errors["relocate"],
                       errors["release"], errors["estimate"], in_box, fallen, sim_s,
                       time.perf_counter() - wall0, detail, landing)


def placements(n: int, seed: int) -> list[tuple[float, float, float]]:
    """(U, V, robot distance) for n trials: uniform along the side, 0.10-0.30 m in, the robot 1.5-2.5 m away."""
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(*CAN_ALONG_RANGE_M)), float(rng.uniform(*CAN_FROM_EDGE_RANGE_M)),
             float(rng.uniform(*ROBOT_DISTANCE_RANGE_M))) for _ in range(n)]


def run_trials(trials: list[tuple[float, float, float]], workers: int = 1,
               progress=None, look_after: bool = True, run=None) -> Iterator:
    """Each (U, V, distance) as a trial of `run` (default: this module's run_trial, with `look_after`; the trash
    experiment's takes its own three numbers), in `workers` spawned processes (each trial builds its own robot: the
    results are the same however many run at once); yields them as they finish."""
    if run is None:
        run = functools.partial(run_trial, look_after=look_after)
    if workers <= 1:
        for i, (u, v, d) in enumerate(trials):
            yield run(u, v, d, trial=i, progress=progress)
        return
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = [pool.submit(run, u, v, d, i) for i, (u, v, d) in enumerate(trials)]
        for future in as_completed(futures):
            yield future.result()


def write_csv(results: list[TrialResult], path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(CSV_COLUMNS)
        for r in results:
            d = asdict(r)
            w.writerow(["" if d[c] is None else (f"{d[c]:.4g}" if isinstance(d[c], float) else d[c])
                        for c in CSV_COLUMNS])


def summary_table(results: list[TrialResult]) -> str:
    def cell(v):
        return "-" if v is None else f"{v:6.1f}"

    lines = ["trial   U [m]  V [m]  D [m]  locate [mm]  release [mm]  in box  sim [s]  wall [s]  verdict"]
    for r in results:
        lines.append(f"{r.trial:5d}  {r.can_u_m:+.3f}  {r.can_v_m:.3f}  {r.robot_distance_m:.2f}  "
                     f"{cell(r.can_location_error_mm):>11}  {cell(r.release_error_mm):>12}  "
                     f"{'yes' if r.in_box else 'no':>6}  {r.sim_time_s:7.1f}  {r.wall_time_s:8.1f}  {r.verdict}")
    for label, key in (("can location error", "can_location_error_mm"), ("release error", "release_error_mm")):
        v = np.array([getattr(r, key) for r in results if getattr(r, key) is not None])
        if len(v):
            lines.append(f"{label}: median {np.median(v):.1f} mm, max {v.max():.1f} mm over {len(v)} trials")
    return "\n".join(lines)


def trial_line(r: TrialResult) -> str:
    return f"{r.verdict} ({r.message})"


def _verbose(msg: str) -> None:
    print(msg, flush=True)


def main(argv) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="hrp2-console experiment expo",
                                description="The EXPO 2005 task of [OP] VI: take the can, throw it in the box.")
    p.add_argument("--can", nargs=2, type=float, metavar=("U", "V"),
                   help="one trial: the can U [m] along the near long side from its middle, V [m] in from the edge")
    p.add_argument("--distance", type=float, default=2.0, help="robot to the table's near edge [m] (one trial)")
    p.add_argument("--trials", type=int, help="random trials")
    p.add_argument("--seed", type=int, default=2005, help="seed of the random placements")
    p.add_argument("--out", type=Path, default=Path("out/experiments"), help="where the CSV goes")
    p.add_argument("--verbose", action="store_true", help="print each behaviour's outcome")
    p.add_argument("--workers", type=int, default=1, choices=range(1, 65), metavar="N",
                   help="trials run in N processes at once (1-64; the results do not depend on it)")
    args = p.parse_args(list(argv))
    log = _verbose if args.verbose else None
    if args.can is not None:
        u, v = args.can
        r = run_trial(u, v, args.distance, progress=log)
        print(f"expo trial: can U {u:+.3f} m, V {v:.3f} m, robot {args.distance:.2f} m from the table; "
              f"{r.sim_time_s:.1f} s simulated in {r.wall_time_s:.1f} s")
        print(trial_line(r))
        return 0 if r.succeeded else 1
    n = args.trials or 20
    results = []
    for done, r in enumerate(run_trials(placements(n, args.seed), args.workers, progress=log), start=1):
        results.append(r)
        print(f"[{done}/{n}] trial {r.trial}: U {r.can_u_m:+.3f} V {r.can_v_m:.3f} D {r.robot_distance_m:.2f}: "
              f"{trial_line(r)} ({r.sim_time_s:.0f} s sim, {r.wall_time_s:.0f} s wall)", flush=True)
    results.sort(key=lambda r: r.trial)
    path = args.out / f"expo-seed{args.seed}-{n}.csv"
    write_csv(results, path)
    print(summary_table(results))
    print(f"CSV: {path}")
    ok = sum(r.succeeded for r in results)
    print(f"{ok}/{n} succeeded")
    return 0 if ok == n else 1
