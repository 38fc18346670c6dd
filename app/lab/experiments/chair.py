"""The chair of [OP] VI, Fig. 8: `hrp2-console experiment chair [--trials N --seed S --workers W]`.

"Manipulating a chair using its left hand". A chair (robot/scene_chair.py: a free body on four felt-padded legs
that slides, and tips if pushed too high) stands in front of the robot, its backrest toward it, at a seeded
place and yaw (a simulator operation, as the human at the console would see it, like `experiment floor`'s
object). A scripted operator streams the left hand's stick (floor_object.Operator: closed-loop on the encoder
hand pose, at a human's speeds) and presses the gripper buttons: the open hand behind the backrest's rail,
forward onto it, `grasp`, then pushes the chair PUSH_M along its own forward axis to the goal, `release`,
and backs the hand off. The robot stands where it is: the goal is within the arm's reach.

The verdict reads the simulator: the chair's floor point within GOAL_TOL_M of its goal, its yaw within
GOAL_TOL_DEG of the start's, upright (tilt < UPRIGHT_TOL_DEG), and the robot not fallen.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

import robot.generate as gen
from app.lab.experiments.fig8_plots import plot_top_view
from app.lab.experiments.floor_object import OPEN_GAP_M, SETTLE_S, Operator, rotation_z
from app.lab.experiments.seeded import one_trial, run_seeded, seeded_parser
from app.service import OperatorService
from app.service.local import LocalRobot
from robot.scene_chair import CHAIR_RAIL_HEIGHT_M, CHAIR_RAIL_RADIUS_M, CHAIR_START_M, rail_x_in_chair_m

PUSH_M = 0.12  # [m] the chair's goal: this far along its forward axis from where it stood
GOAL_TOL_M = 0.03  # [m] the verdict: the chair's floor point this close to the goal
GOAL_TOL_DEG = 10.0  # [deg] ... its yaw this close to the start's
UPRIGHT_TOL_DEG = 5.0  # [deg] ... and its vertical axis this close to vertical
#: Seeded placements: the chair's floor point this far from CHAIR_START_M [m] (along x, along y) and yaw [deg].
OFFSET_X_RANGE_M = (-0.03, 0.03)
OFFSET_Y_RANGE_M = (-0.05, 0.05)
YAW_RANGE_DEG = (-10.0, 10.0)
GRIP_FORCE_N = 14.0  # [N] the grasp button's fingertip force (the floor task's)
PUSH_SPEED_M_S = 0.04  # [m/s] the stick's speed pushing (the chair slides at ~10 N)
APPROACH_M = 0.08  # [m] the open hand this far behind the rail before it closes in
#: [m, F] the hand first goes forward and up here, its orientation kept, then turns to the grasp's (turned on
#: the way from its hanging pose, the upper arm met the chest)
RAISE_HAND_M = (0.22, 0.32, 0.75)



@dataclass
class ChairResult:
    trial: int
    offset_x_m: float
    offset_y_m: float
    yaw_deg: float
    verdict: str  # "succeeded" or "failed: why"
    goal_error_m: float
    yaw_error_deg: float
    tilt_deg: float
    max_tilt_deg: float
    fallen: bool
    sim_time_s: float
    wall_time_s: float
    message: str
    start_m: tuple[float, float] = (0.0, 0.0)  # the chair's floor point, world (simulator)
    end_m: tuple[float, float] = (0.0, 0.0)
    goal_m: tuple[float, float] = (0.0, 0.0)

    @property
    def succeeded(self) -> bool:
        return self.verdict == "succeeded"


def hand_rotation(yaw_rad: float) -> np.ndarray:
    """(3, 3) the left hand on the rail of a chair turned `yaw_rad`: pointing along the chair's forward axis (its
    z axis backward), the jaws (its x axis, up: the hanging hand pitched up 90 deg) closing vertically."""
    x_hand = np.array([0.0, 0.0, 1.0])
    z_hand = -rotation_z(yaw_rad)[:, 0]
    return np.column_stack([x_hand, np.cross(z_hand, x_hand), z_hand])


def rail_in_hand_m() -> np.ndarray:
    """(3,) the rail's axis relative to larm_end in the hand frame, centred between the open jaws (the 85 mm grasp
    centre moved toward the finger by the open gap's half less the rail's radius)."""
    params = gen.load_parameters()
    c_85, _ = gen.grasp_centre(params, "LARM")
    c_rail, _ = gen.grasp_centre(params, "LARM", CHAIR_RAIL_RADIUS_M)
    in_hand = np.array(c_rail) - np.array(c_85)
    u = -in_hand / max(float(np.linalg.norm(in_hand)), 1e-9)
    return in_hand + (OPEN_GAP_M / 2 - CHAIR_RAIL_RADIUS_M) * u


def tilt_deg(quat_wxyz) -> float:
    """The angle of a body's z axis from the vertical [deg]."""
    w, x, y, z = quat_wxyz
    return math.degrees(2.0 * math.asin(min(1.0, math.hypot(x, y))))


def yaw_deg(quat_wxyz) -> float:
    w, x, y, z = quat_wxyz
    return math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


def run_trial(offset_x_m: float = 0.0, offset_y_m: float = 0.0, yaw_deg_: float = 0.0, trial: int = 0,
              progress=None) -> ChairResult:
    """One trial: the chair at CHAIR_START_M + (offset_x_m, offset_y_m) turned yaw_deg_, pushed PUSH_M."""
    wall0 = time.perf_counter()
    robot = LocalRobot("chair", speed=None)
    service = OperatorService(robot)
    plant = robot.plant
    yaw = math.radians(yaw_deg_)
    start = plant.place_object("chair", (CHAIR_START_M[0] + offset_x_m, CHAIR_START_M[1] + offset_y_m), yaw)
    forward = rotation_z(yaw)[:, 0]
    goal = start + PUSH_M * forward
    robot.run_for(SETTLE_S)
    op = Operator(robot, service, progress)
    message, max_tilt = "", 0.0
    try:
        # what the operator sees: the rail relative to the soles' midpoint (the robot stands at the origin)
        feet = 0.5 * (plant.data.body("RLEG_LINK5").xpos + plant.data.body("LLEG_LINK5").xpos)
        rail = start + rotation_z(yaw) @ np.array([rail_x_in_chair_m(), 0.0, CHAIR_RAIL_HEIGHT_M])
        rail_f = rail - np.array([feet[0], feet[1], 0.0])
        R_hand = hand_rotation(yaw)
        grasp_at = rail_f - R_hand @ rail_in_hand_m()
        op.say(f"rail seen at ({rail_f[0]:.3f}, {rail_f[1]:.3f}, {rail_f[2]:.3f}) m from the feet centre")
        op.press("release", {"hand": "lhand"})  # open the gripper
        p0, R0 = op.measured("larm_end")
        op.say(f"left hand at rest: {np.round(p0, 3)}, axes {np.round(R0, 2).tolist()}")
        op.drive(hand_m=np.array(RAISE_HAND_M), point="lhand", label="hand forward (orientation kept)", tol_m=0.01)
        op.drive(hand_m=np.array(RAISE_HAND_M), hand_R=R_hand, point="lhand", label="rotate", tol_m=0.01,
                 timeout_s=15.0, required=True)
        op.drive(hand_m=grasp_at - APPROACH_M * forward + np.array([0.0, 0.0, 0.03]), hand_R=R_hand,
                 point="lhand", label="behind the rail", tol_m=0.01, timeout_s=15.0, required=True)
        op.drive(hand_m=grasp_at - APPROACH_M * forward, hand_R=R_hand, point="lhand", label="pre-grasp",
                 tol_m=0.005, required=True)
        op.drive(hand_m=grasp_at, hand_R=R_hand, point="lhand", label="onto the rail", linear_m_s=0.04,
                 tol_m=0.005, required=True)
        op.wait(0.3)
        if op.press("grasp", {"hand": "lhand", "force_n": GRIP_FORCE_N}).state != "succeeded":
            raise RuntimeError("the grasp failed")
        p_hand, _ = op.measured("larm_end")
        op.drive(hand_m=p_hand + PUSH_M * forward, hand_R=R_hand, point="lhand", label="push",
                 linear_m_s=PUSH_SPEED_M_S, tol_m=0.005, timeout_s=15.0)
        max_tilt = max(max_tilt, tilt_deg(plant.object_pose("chair")[1]))
        op.wait(0.3)
        if op.press("release", {"hand": "lhand"}).state != "succeeded":
            raise RuntimeError("the release failed")
        p_hand, _ = op.measured("larm_end")
        op.drive(hand_m=p_hand - APPROACH_M * forward, hand_R=R_hand, point="lhand", label="back off", tol_m=0.01)
        op.wait(1.0)
    except Exception as exc:  # a fall, a fault, a refused setpoint: the run ends there
        message = str(exc)
    end, quat = plant.object_pose("chair")
    error_m = float(np.linalg.norm(end[:2] - goal[:2]))
    dyaw = abs((yaw_deg(quat) - yaw_deg_ + 180.0) % 360.0 - 180.0)
    tilt = tilt_deg(quat)
    max_tilt = max(max_tilt, tilt)
    sim_s = float(robot.loop.snapshot.time_s)
    robot.close()
    if not message and not (error_m < GOAL_TOL_M and dyaw < GOAL_TOL_DEG and tilt < UPRIGHT_TOL_DEG):
        message = (f"the chair ended {1e3 * error_m:.0f} mm from its goal, turned {dyaw:.1f} deg, tilted "
                   f"{tilt:.1f} deg")
    verdict = "succeeded" if not message else f"failed: {message}"
    return ChairResult(trial, offset_x_m, offset_y_m, yaw_deg_, verdict, error_m, dyaw, tilt, max_tilt, op.fallen,
                       sim_s, time.perf_counter() - wall0, message, tuple(start[:2]), tuple(end[:2]), tuple(goal[:2]))


def placements(n: int, seed: int) -> list[tuple[float, float, float]]:
    """(x offset [m], y offset [m], yaw [deg]) for n trials, uniform in their ranges."""
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(*OFFSET_X_RANGE_M)), float(rng.uniform(*OFFSET_Y_RANGE_M)),
             float(rng.uniform(*YAW_RANGE_DEG))) for _ in range(n)]


def summary_table(results: list[ChairResult]) -> str:
    lines = ["trial  dx [m]  dy [m]  yaw [deg]  goal error [mm]  yaw error [deg]  tilt [deg]  sim [s]  wall [s]  "
             "verdict"]
    for r in results:
        lines.append(f"{r.trial:5d}  {r.offset_x_m:+.3f}  {r.offset_y_m:+.3f}  {r.yaw_deg:9.1f}  "
                     f"{1e3 * r.goal_error_m:15.1f}  {r.yaw_error_deg:15.1f}  {r.max_tilt_deg:10.1f}  "
                     f"{r.sim_time_s:7.1f}  {r.wall_time_s:8.1f}  {r.verdict}")
    return "\n".join(lines)


def main(argv) -> int:
    p = seeded_parser("hrp2-console experiment chair",
                      f"[OP] Fig. 8: the left hand grasps a chair's backrest and pushes it {PUSH_M:g} m to its goal.",
                      "chair", ("DX", "DY", "YAW_DEG"),
                      "one trial: the chair DX, DY [m] from its start place, turned YAW_DEG [deg]")
    args = p.parse_args(list(argv))
    if args.chair is not None:
        return one_trial(lambda progress: run_trial(*args.chair, progress=progress), args.verbose, summary_table)
    results = run_seeded(args, placements, run_trial, summary_table)
    ok = sum(r.succeeded for r in results)
    if args.png is not None:
        plot_top_view(args.png, f"experiment chair: {ok}/{args.trials} within {1e3 * GOAL_TOL_M:.0f} mm of the goal "
                      f"(seed {args.seed})", [r.start_m for r in results], [r.end_m for r in results],
                      [r.succeeded for r in results], [r.goal_m for r in results], GOAL_TOL_M)
        print(f"PNG: {args.png}")
    print(f"{ok}/{args.trials} succeeded")
    return 0 if ok == args.trials else 1
