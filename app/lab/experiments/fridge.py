"""The fridge task of [OP] VI, Fig. 8: `hrp2-console experiment fridge` (one trial, or `--trials N --seed S`).

"Taking out a can from the fridge with its right hand holding the fridge door and the left hand taking out the
can." A trial places the fridge (shifted and turned) and the can on its shelf (simulator operations), then:
`locate_handle`; `open_door` (the right hand grasps the handle and pulls the door open along its arc, then
holds it); while the door opens, a scripted operator already streams the left hand's stick (Eq. 5 for two
points: the behaviour's twist at rhand and the stick's at lhand in the same ticks, counted from the operation
layer's status); with the door held, `locate_can` (the operator says where to look: the shelf), then the stick
takes the left hand to the can, the grasp button closes it, the stick lifts the can and draws it out.

The operator closes the loop on what the console shows (the hand's pose from the encoders, the located can).
The simulator's poses only give the verdict: the can out of the cabinet (in front of its front face) and off
the shelf and floor (held), the door open more than DOOR_OPEN_MIN_DEG, the robot standing."""

from __future__ import annotations

import math
import multiprocessing
import time
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import robot.generate as gen
from app.lab.experiments.floor_object import Operator
from app.service import OperatorService
from app.service.local import LocalRobot
from behaviors.hand_geometry import HAND_PITCH_DEG
from behaviors.servo import rot_z
from robot import scene_fridge as fridge

SETTLE_S = 2.5  # [s] standing before the first command (the AutoBalancer starts in 2 s)
DOOR_OPEN_MIN_DEG = 20.0  # the verdict: the door open at least this far at the end
OPEN_DEG = 40.0  # open_door's arc
HOLD_S = 60.0  # open_door holds the door this long at most (the trial ends before)
RUN_TIMEOUT_S = 60.0  # [s] of simulated time for open_door to reach its hold
#: The fridge's pose is varied by these (uniform) [m, m, deg]; the can's y on the shelf by FRIDGE_CAN_Y_RANGE_M.
SHIFT_X_RANGE_M = (-0.02, 0.02)
SHIFT_Y_RANGE_M = (-0.02, 0.02)
YAW_RANGE_DEG = (-4.0, 4.0)
#: Where the operator asks the robot to look for the can: the shelf's middle in front, at can height (world; the
#: fridge's usual place, robot/scene_fridge.py)
CAN_LOOK_M = (fridge.FRIDGE_HINGE_M[0] + 0.05, fridge.FRIDGE_HINGE_M[1] + 0.40, fridge.FRIDGE_SHELF_TOP_M + 0.06)
#: The left hand (F) [m]: raised where it hangs while the door opens, then forward (its orientation kept), then
#: turned to the grasp's orientation there (the right hand's path to the can on the table, mirrored: turned on
#: the way, the wrist met the chest)
LHAND_READY_M = (0.15, 0.30, 0.82)
LHAND_VIA_M = (0.30, 0.30, 0.80)
LHAND_ROTATE_AT_M = (0.36, 0.28, 0.82)
#: The left hand's grasp: pitched down as the right hand's on the table, turned toward the body's middle [deg]
LHAND_YAW_DEG = -45.0  # (-10 and -30: the left forearm met the door's edge or its joints their limits)
PRE_GRASP_BACK_M = 0.10  # [m] along the approach
#: [rad] the operator leans the waist forward for the left hand to reach into the fridge (the can 0.63 m ahead;
#: standing upright the hand takes a can at most 0.56 m ahead), slowly: [rad/s]
LEAN_RAD = math.radians(15.0)
LEAN_RATE_RAD_S = math.radians(8.0)
GRASP_PAST_CENTRE_M = 0.010  # [m] the palm seats the can (take_can's)
GRASP_ABOVE_CENTRE_M = 0.015  # [m] (take_can's)
LIFT_M = 0.03  # [m] the can lifted off the shelf
OUT_M = (0.25, 0.18, 0.85)  # [m, F] the held can drawn out to here (the hand point)
HELD_MIN_Z_M = 0.3  # [m] the can's centre above this at the end: held, not dropped
THROUGH = ("can", "door")  # how far a trial goes: the can out (the task), or the door held open
MIRROR_Y = np.diag([1.0, -1.0, 1.0])


def lhand_grasp_rotation_feet(yaw_deg: float = LHAND_YAW_DEG) -> np.ndarray:
    """(3, 3) the left hand's grasp orientation in F: the right hand's can grasp (fingers forward and
    HAND_PITCH_DEG down, the jaws across) mirrored (the left hand's frame is the right's mirror image), turned."""
    a = math.radians(HAND_PITCH_DEG)
    approach = np.array([math.cos(a), 0.0, -math.sin(a)])
    z_hand = -approach
    x_hand = np.array([0.0, 1.0, 0.0])
    R_right = np.column_stack([x_hand, np.cross(z_hand, x_hand), z_hand])
    return rot_z(math.radians(yaw_deg)) @ MIRROR_Y @ R_right @ MIRROR_Y


def _can_in_lhand_m() -> np.ndarray:
    params = gen.load_parameters()
    c_85, _ = gen.grasp_centre(params, "LARM")
    c_can, _ = gen.grasp_centre(params, "LARM", gen.CAN_DIAMETER_M / 2)
    return np.array(c_can) - np.array(c_85)


@dataclass
class FridgeResult:
    trial: int
    shift_x_m: float
    shift_y_m: float
    yaw_deg: float
    can_y_m: float  # the can's y on the shelf, fridge frame
    verdict: str  # "succeeded" or "failed: why"
    door_deg: float  # the door's angle at the end
    can_out_m: float  # how far the can's centre is in front of the cabinet's front face (> 0: out)
    can_z_m: float
    handle_error_mm: float | None  # the located handle vs where it is
    can_error_mm: float | None  # the located can vs where it is
    two_point_ticks: int  # ticks with open_door's twist at rhand and the stick's at lhand (Eq. 5, two points)
    fallen: bool
    sim_time_s: float
    wall_time_s: float
    series: list = field(default_factory=list, repr=False)  # FridgeOperator.series

    @property
    def succeeded(self) -> bool:
        return self.verdict == "succeeded"


class FridgeOperator(Operator):
    """The floor task's scripted operator, also counting the ticks in which a behaviour drives the right hand
    and the stick the left (from the operation layer's status)."""

    def __init__(self, robot, service, progress=None, door_deg=None) -> None:
        super().__init__(robot, service, progress)
        self.two_point_ticks = 0
        self.door_deg = door_deg  # () -> the door's angle [deg] from the simulator, for the record only
        #: per tick: time [s], door [deg], |rhand behaviour twist| [m/s], |lhand stick twist| [m/s]
        self.series: list[tuple[float, float, float, float]] = []

    def step(self) -> None:
        super().step()
        snap = self.robot.loop.snapshot
        op = snap.layers.get("op")
        right_m_s = left_m_s = 0.0
        if op is not None and op.active:
            right, left = op.points["rhand"], op.points["lhand"]
            right_m_s = float(np.linalg.norm(np.asarray(right.behavior)[:3]))
            left_m_s = float(np.linalg.norm(np.asarray(left.motion)[:3]))
            if np.any(np.asarray(right.behavior) != 0.0) and np.any(np.asarray(left.motion) != 0.0):
                self.two_point_ticks += 1
        if self.door_deg is not None:
            self.series.append((float(snap.time_s), self.door_deg(), right_m_s, left_m_s))

    def until_phase(self, run_id: int, phases: tuple[str, ...], timeout_s: float) -> None:
        """Step until the run is in one of `phases`; a run that ended (or did not get there) ends the trial."""
        for _ in range(int(timeout_s / self.robot.loop.dt_control_s)):
            status = self.service.get_run(run_id)
            if status.state != "running":
                raise RuntimeError(f"open_door {status.state}: {status.message}")
            if status.result.get("phase") in phases:
                return
            self.step()
        raise RuntimeError(f"open_door not at {phases} after {timeout_s} s")


def fridge_pose(shift_x_m: float, shift_y_m: float, yaw_deg: float) -> tuple[np.ndarray, float]:
    """The fridge frame's origin (the hinge, on the floor) [m] and yaw [rad] in the world."""
    return np.array([fridge.FRIDGE_HINGE_M[0] + shift_x_m, fridge.FRIDGE_HINGE_M[1] + shift_y_m, 0.0]), \
        math.radians(yaw_deg)


def in_fridge(p_world, origin, yaw_rad: float) -> np.ndarray:
    """(3,) a world point in the fridge frame."""
    return rot_z(yaw_rad).T @ (np.asarray(p_world, dtype=float) - origin)


class _Done(Exception):
    """The trial went as far as asked."""


def run_trial(shift_x_m: float = 0.0, shift_y_m: float = 0.0, yaw_deg: float = 0.0,
              can_y_m: float = fridge.FRIDGE_CAN_IN_FRIDGE_M[1], trial: int = 0, progress=None,
              through: str = "can") -> FridgeResult:
    """One trial: the fridge shifted and turned about its hinge, the can `can_y_m` from the hinge on the shelf.
    `through="door"` ends once the door is held open and the can located (the verdict: the door open, standing)."""
    if through not in THROUGH:
        raise ValueError(f"through={through!r}: one of {THROUGH}")
    wall0 = time.perf_counter()
    robot = LocalRobot("fridge", speed=None)
    service = OperatorService(robot)
    plant = robot.plant
    origin, yaw = fridge_pose(shift_x_m, shift_y_m, yaw_deg)
    plant.place_object("fridge", origin, yaw)
    can_local = np.array([fridge.FRIDGE_CAN_IN_FRIDGE_M[0], can_y_m,
                          fridge.FRIDGE_SHELF_TOP_M + gen.CAN_HEIGHT_M / 2 + 0.001])
    can_true = plant.place_object("can", origin + rot_z(yaw) @ can_local, yaw)
    door_adr = plant.model.sensor("fridge_door_angle").adr[0]
    op = FridgeOperator(robot, service, progress,
                        door_deg=lambda: math.degrees(float(plant.data.sensordata[door_adr])))
    handle_error = can_error = None
    message = ""
    try:
        op.wait(SETTLE_S)
        if op.press("locate_handle").state != "succeeded":
            raise RuntimeError("the handle was not located")
        rec = robot.host.recognitions["fridge_handle"]
        handle_true = origin + rot_z(yaw) @ np.array([-fridge.FRIDGE_DOOR_THICKNESS_M - fridge.FRIDGE_HANDLE_STANDOFF_M,
                                                      fridge.FRIDGE_HANDLE_FROM_HINGE_M, fridge.FRIDGE_HANDLE_Z_M[1]])
        handle_error = 1e3 * float(np.linalg.norm(np.array(rec["position_m"]) - handle_true))
        run_id = service.run_behavior("open_door", {"locate": False, "open_deg": OPEN_DEG, "hold_s": HOLD_S})
        op.until_phase(run_id, ("pull",), RUN_TIMEOUT_S)
        # the door opens; the operator raises the left hand meanwhile (Eq. 5: both hands in the same ticks)
        pl, Rl = op.measured("larm_end")
        op.drive(hand_m=np.array(LHAND_READY_M), hand_R=Rl, point="lhand", label="left hand up", tol_m=0.01)
        op.until_phase(run_id, ("hold",), RUN_TIMEOUT_S)
        op.say(f"door held; two-point ticks so far {op.two_point_ticks}")
        look = {"x_m": CAN_LOOK_M[0], "y_m": CAN_LOOK_M[1], "z_m": CAN_LOOK_M[2]}
        if op.press("locate_can", look).state != "succeeded":
            raise RuntimeError("the can was not located")
        can_seen = np.array(robot.host.recognitions["can"]["position_m"])
        can_error = 1e3 * float(np.linalg.norm(can_seen - can_true))
        if through == "door":
            raise _Done
        # the robot has not walked: the feet frame is where it started, the world's origin
        R = lhand_grasp_rotation_feet()
        approach = -R[:, 2]
        grasp = can_seen + np.array([0.0, 0.0, GRASP_ABOVE_CENTRE_M]) - R @ _can_in_lhand_m() \
            + GRASP_PAST_CENTRE_M * approach
        op.drive(hand_m=np.array(LHAND_VIA_M), hand_R=Rl, point="lhand", label="left hand forward", tol_m=0.01,
                 required=True)
        op.drive(hand_m=np.array(LHAND_ROTATE_AT_M), hand_R=R, point="lhand", label="left hand turned", tol_m=0.01,
                 tol_rad=math.radians(2.0), required=True)
        if op.press("release", {"hand": "lhand"}).state != "succeeded":  # the gripper opened for the can
            raise RuntimeError("the left gripper did not open")
        op.drive(waist_pitch_rad=LEAN_RAD, angular_rad_s=LEAN_RATE_RAD_S, label="lean forward", timeout_s=6.0)
        op.drive(hand_m=grasp - PRE_GRASP_BACK_M * approach, hand_R=R, point="lhand", label="pre-grasp",
                 linear_m_s=0.05, required=True)
        op.drive(hand_m=grasp, hand_R=R, point="lhand", label="grasp", linear_m_s=0.02, required=True)
        if op.press("grasp", {"hand": "lhand"}).state != "succeeded":
            raise RuntimeError("the left hand missed the can")
        op.drive(hand_m=grasp + np.array([0.0, 0.0, LIFT_M]), hand_R=R, point="lhand", label="lift",
                 linear_m_s=0.05, required=True)
        op.drive(hand_m=grasp + np.array([0.0, 0.0, LIFT_M]) - 0.12 * approach, hand_R=R, point="lhand",
                 label="back", linear_m_s=0.05, tol_m=0.01, required=True)
        op.drive(hand_m=np.array(OUT_M), hand_R=R, point="lhand", label="out", linear_m_s=0.05, tol_m=0.01,
                 required=True)
        op.drive(waist_pitch_rad=0.0, angular_rad_s=LEAN_RATE_RAD_S, label="upright", timeout_s=6.0)
        op.wait(1.0)
    except _Done:
        pass
    except Exception as exc:  # a fall, a fault, a refused setpoint, a failed step: the trial ends there
        message = str(exc)
    door_deg = math.degrees(float(plant.data.sensordata[plant.model.sensor("fridge_door_angle").adr[0]]))
    can_end = plant.object_pose("can")[0]
    can_out = -float(in_fridge(can_end, origin, yaw)[0])
    sim_s = float(robot.loop.snapshot.time_s)
    robot.close()
    if not message and door_deg < DOOR_OPEN_MIN_DEG:
        message = f"the door is open {door_deg:.1f} deg, less than {DOOR_OPEN_MIN_DEG} deg"
    if not message and through == "can" and not (can_out > 0.0 and can_end[2] > HELD_MIN_Z_M):
        message = f"the can is at ({can_end[0]:.3f}, {can_end[1]:.3f}, {can_end[2]:.3f}) m, not out and held"
    verdict = "succeeded" if not message else f"failed: {message}"
    return FridgeResult(trial, shift_x_m, shift_y_m, yaw_deg, can_y_m, verdict, door_deg, can_out,
                        float(can_end[2]), handle_error, can_error, op.two_point_ticks, op.fallen, sim_s,
                        time.perf_counter() - wall0, op.series)


def placements(n: int, seed: int) -> list[tuple[float, float, float, float]]:
    """(shift x, shift y [m], yaw [deg], can y [m]) for n trials, uniform in the stated ranges."""
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(*SHIFT_X_RANGE_M)), float(rng.uniform(*SHIFT_Y_RANGE_M)),
             float(rng.uniform(*YAW_RANGE_DEG)), float(rng.uniform(*fridge.FRIDGE_CAN_Y_RANGE_M)))
            for _ in range(n)]


def _trial(args: tuple) -> FridgeResult:
    """One trial from (index, placement, through) in a worker process."""
    i, (dx, dy, yaw, can_y), through = args
    return run_trial(dx, dy, yaw, can_y, trial=i, through=through)


def run_trials(trials: list[tuple[float, float, float, float]], workers: int = 1, progress=None,
               through: str = "can") -> Iterator[FridgeResult]:
    """Each placement as a trial, in `workers` spawned processes (each builds its own robot: the results do not
    depend on how many run at once); yields them as they finish."""
    if workers <= 1:
        for i, (dx, dy, yaw, can_y) in enumerate(trials):
            yield run_trial(dx, dy, yaw, can_y, trial=i, progress=progress, through=through)
        return
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = [pool.submit(_trial, (i, t, through)) for i, t in enumerate(trials)]
        for future in as_completed(futures):
            yield future.result()


def trial_line(r: FridgeResult) -> str:
    def mm(v):
        return "-" if v is None else f"{v:.1f} mm"

    return (f"trial {r.trial}: fridge ({r.shift_x_m:+.3f}, {r.shift_y_m:+.3f}) m {r.yaw_deg:+.1f} deg, can y "
            f"{r.can_y_m:.3f} m: door {r.door_deg:.1f} deg, can out {1e3 * r.can_out_m:.0f} mm, z {r.can_z_m:.3f} m; "
            f"handle located {mm(r.handle_error_mm)} off, can {mm(r.can_error_mm)} off; two-point ticks "
            f"{r.two_point_ticks}; {r.sim_time_s:.0f} s sim in {r.wall_time_s:.0f} s: {r.verdict}")


def main(argv) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="hrp2-console experiment fridge",
                                description="[OP] Fig. 8: the right hand opens the fridge door and holds it, the "
                                            "left hand (the operator's stick) takes the can out.")
    p.add_argument("--trials", type=int, help="seeded trials (default: one trial at the nominal placement)")
    p.add_argument("--seed", type=int, default=8, help="seed of the placements")
    p.add_argument("--workers", type=int, default=1, choices=range(1, 65), metavar="N",
                   help="trials run in N processes at once (1-64)")
    p.add_argument("--through", choices=THROUGH, default="can",
                   help="door: end once the door is held open and the can located")
    p.add_argument("--verbose", action="store_true", help="print each step (one process only)")
    p.add_argument("--plot", type=Path, help="one trial: write its door angle and the two hands' twists as a PNG")
    args = p.parse_args(list(argv))
    log = (lambda m: print(m, flush=True)) if args.verbose else None
    trials = placements(args.trials, args.seed) if args.trials else [(0.0, 0.0, 0.0, fridge.FRIDGE_CAN_IN_FRIDGE_M[1])]
    results = []
    for r in run_trials(trials, args.workers, progress=log, through=args.through):
        results.append(r)
        print(trial_line(r), flush=True)
    if args.plot is not None and len(results) == 1:
        from app.lab.experiments.fridge_plot import plot_fridge

        plot_fridge(results[0].series, args.plot)
        print(f"plot: {args.plot}")
    ok = sum(r.succeeded for r in results)
    door_ok = sum(r.door_deg >= DOOR_OPEN_MIN_DEG and not r.fallen for r in results)
    print(f"door open >= {DOOR_OPEN_MIN_DEG:.0f} deg, standing: {door_ok}/{len(results)}")
    print(f"{ok}/{len(results)} succeeded")
    return 0 if ok == len(results) else 1
