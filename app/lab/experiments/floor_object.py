"""The joystick-only EXPO task of [OP] VI, Fig. 7(c): `hrp2-console experiment floor`.

"The operator operates the robot's right hand using joysticks to put the unknown bag on the table after
approaching to the table using behavior level command Approach Table." The unknown object is placed on the
floor beside the approach stance (a simulator operation, as the human would see it), `approach_table` runs,
then a scripted operator streams stick setpoints every tick through `OperatorService.put_setpoint` (the path
of WS /ws/operator) and presses the gripper buttons (`grasp`, `release`): rotate the hand while standing,
squat and pitch the waist, reach down beside the object, grasp, lift, turn the forearm back through waypoints
(squatting), stand, raise the object behind the table's edge, over the table, lower, release, withdraw.

The operator closes the loop on what a human at the console sees: the robot's own hand pose (forward
kinematics of the encoders with the KalmanFilter attitude, relative to the soles' midpoint) and where the
object was placed. Stick speeds are a human's: at most 0.1 m/s and 20 deg/s. The simulator's pose of the
object is read only for the verdict: it stands on the table top (centre at 0.70 m + half its height, upright),
inside the top's outline, did not move as the hand withdrew after the release, and the robot has not fallen."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

import robot.generate as gen
from app.service import OperatorService
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint
from behaviors.servo import rotation_vector
from controller.kinematics.model import RobotKinematics, frame_from_soles_midpoint
from robot.names import JOINT_NAMES

SETTLE_S = 2.5  # [s] standing before the first command (the AutoBalancer starts in 2 s)
STANDOFF_M = 0.3  # [m] approach_table's feet centre to the table's near edge (its default)
LINEAR_M_S = 0.1  # [m/s] the fastest stick speed used (a human's)
ANGULAR_RAD_S = math.radians(20.0)  # [rad/s] likewise for rotations
STICK_RAMP_1_S = 2.0  # [1/s] the hand stick goes from rest to full deflection in 0.5 s at the fastest
GAIN_1_S = 2.0  # [1/s] stick deflection per metre (or radian) of error: the operator slows near the target
#: The object on the floor, relative to the stance (feet centre after approach_table, F axes) [m]: ahead of the
#: right foot, in reach of the squatting robot's right hand.
OBJECT_FLOOR_IN_STANCE_M = (0.24, -0.33)
#: Where the operator puts it on the table top, relative to the stance [m]: 0.10 m in from the near edge.
OBJECT_TABLE_IN_STANCE_M = (STANDOFF_M + 0.10, -0.25)
VIA_M = (0.30, -0.30, 0.80)  # [m] the hand first goes forward and up here, its orientation kept (as take_can)
ROTATE_AT_M = (0.36, -0.28, 0.82)  # [m] ... then turns to the grasp orientation here (take_can's pre-grasp)
BACK_M = (0.18, -0.30, 0.82)  # [m] ... and back: going down, the fingers clear the table top's near edge
SQUAT_HAND_M = (0.18, -0.34, 0.44)  # [m] the hand goes down to here while the robot squats
#: The hand pitched this far down (the can's grasp on the table is 30 deg): with the arm stretched down to the
#: floor the hand lies nearly along the forearm; the same orientation puts the object down upright.
HAND_PITCH_RAD = math.radians(65.0)
LEFT_HAND_SHIFT_M = (0.05, 0.05, 0.05)  # [m] the left hand forward, out and up, clear of the left thigh
#: After the lift, squatting: the hand (position [m], (yaw, pitch, roll) [deg] from the grasp orientation). From
#: the floor the forearm is turned 90 deg (RARM_JOINT4 at its limit) and lifting straightens the elbow, so
#: standing up stops on that limit at hand height 0.57 m. Out to the right and back while the hand turns -30 deg
#: about the vertical, the forearm turns back and the elbow bends. Planned on the robot's kinematic model: a
#: joint-space line from the lift's arm posture to a solution of the last pose with RARM_JOINT4 at 14 deg (the
#: object within 12 deg of upright along it), sampled at fifths; then the fourth point moved 1 cm forward and the
#: fifth 1 cm up: on the line itself the elbow (RARM_LINK3) passed 10 mm from the chest, 5 mm outside the
#: CollisionDetector's margin, and a 1 cm change of the approach either way could stop the task; from the moved
#: points the arm turns over away from the chest (its 8 neighbours 5-10 mm off all succeed).
UNWIND_WAYPOINTS = (((0.266, -0.369, 0.287), (-6.6, -5.5, -5.2)), ((0.281, -0.382, 0.303), (-13.1, -9.0, -7.6)),
                    ((0.281, -0.377, 0.311), (-19.1, -9.5, -7.2)), ((0.272, -0.358, 0.309), (-24.6, -6.7, -4.5)),
                    ((0.22, -0.33, 0.31), (-30.0, 0.0, 0.0)))
CARRY_YAW_RAD = math.radians(-30.0)  # the hand turned this far about the vertical to carry and place
#: The held object's centre [m]: as the robot stands up, then raised behind the table's near edge (its front
#: corner behind the edge), then its bottom above the table top
STAND_OBJECT_M = (0.22, -0.32, 0.60)
RISE_OBJECT_M = (0.24, -0.28, 0.75)
ABOVE_EDGE_OBJECT_M = (0.25, -0.27, 0.83)
WITHDRAW_PITCH_RAD = math.radians(40.0)  # the empty hand turned up as it backs off (the wrist at 92 deg else)
GRASP_ABOVE_CENTRE_M = 0.07  # [m] the jaws close this far above the object's middle
WAIST_DOWN_M = 0.26  # [m] the squat (0.30 fell)
WAIST_PITCH_RAD = math.radians(25.0)  # the waist pitched forward while squatting (the waist point's most)
WAIST_PITCH_RATE_RAD_S = math.radians(10.0)  # ... slowly: 20 deg/s while squatting set the capture-point flag
OPEN_GAP_M = 0.10  # [m] between the fully open jaws (robot/hrp2/README.md)
LIFTED_MIN_M = 0.05  # [m] the lift (0.10 m of the hand) counts when the object rose this much
HALF_WIDTH_M = gen.UNKNOWN_OBJECT_SIZE_M[1] / 2  # across the jaws
GRIP_FORCE_N = 14.0  # [N] the grasp button's fingertip force: at 10 N the object slid out of the jaws standing up
ON_TABLE_TOL_MM = 5.0  # the verdict: the object's centre within this of resting on the top
UPRIGHT_TOL_DEG = 5.0  # ... its axis within this of vertical
STILL_TOL_MM = 5.0  # ... and not moved by the withdrawing hand more than this after the release


HAND_FRAMES = {"rhand": "rarm_end", "lhand": "larm_end"}  # the operated points' frames
RARM_JOINTS = slice(JOINT_NAMES.index("RARM_JOINT0"), JOINT_NAMES.index("RARM_JOINT5") + 1)


def grasp_rotation_feet(pitch_rad: float) -> np.ndarray:
    """(3, 3) the hand in F for a side grasp pitched `pitch_rad` down: fingers along the approach, the jaws
    closing along y (behaviors.hand_geometry's grasp of the can, there at 30 deg)."""
    approach = np.array([math.cos(pitch_rad), 0.0, -math.sin(pitch_rad)])
    z_hand = -approach
    x_hand = np.array([0.0, 1.0, 0.0])
    return np.column_stack([x_hand, np.cross(z_hand, x_hand), z_hand])


def rotation_z(angle_rad: float) -> np.ndarray:
    """(3, 3) a turn about the vertical."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def turned(ypr_deg) -> np.ndarray:
    """(3, 3) a rotation from yaw, pitch, roll [deg] (about z, then the new y, then the new x)."""
    return Rotation.from_euler("zyx", ypr_deg, degrees=True).as_matrix()


def _object_in_hand_m() -> np.ndarray:
    """(3,) the held object's centre relative to rarm_end in the hand frame, for the object against the fixed
    jaw (the object's half width as the radius of gen.grasp_centre)."""
    params = gen.load_parameters()
    c_85, _ = gen.grasp_centre(params, "RARM")
    c_obj, _ = gen.grasp_centre(params, "RARM", HALF_WIDTH_M)
    return np.array(c_obj) - np.array(c_85)


def _pitch_rad(R: np.ndarray) -> float:
    """Pitch (forward down > 0) of a frame's x axis from the horizontal."""
    return math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))


def _capped(v: np.ndarray, limit: float) -> np.ndarray:
    """v scaled so that no component exceeds `limit` (a stick's range)."""
    m = float(np.max(np.abs(v))) if len(v) else 0.0
    return v if m <= limit else v * (limit / m)


@dataclass
class FloorResult:
    verdict: str  # "succeeded" or "failed: why"
    object_end_m: tuple[float, float, float]
    on_table_error_mm: float  # the object's centre height vs the table top + half height
    tilt_deg: float  # the object's axis from the vertical at the end
    moved_after_release_mm: float | None  # how far the object moved from the release to the end (None: no release)
    lifted_m: float | None  # how far the grasp lifted the object off the floor (None: not got that far)
    fallen: bool
    cp_error_peak_mm: float  # the Stabilizer's largest |CP_ref - CP_act| after approach_table (flag at 40 mm)
    sim_time_s: float
    wall_time_s: float
    log: list[str]

    @property
    def succeeded(self) -> bool:
        return self.verdict == "succeeded"


class _Done(Exception):
    """The run went as far as asked."""


class Operator:
    """A scripted operator at the console: sticks streamed every tick, buttons as behaviours."""

    def __init__(self, robot: LocalRobot, service: OperatorService, progress=None) -> None:
        self.robot = robot
        self.service = service
        self.kin = RobotKinematics()
        self.progress = progress
        self.log: list[str] = []
        self.fallen = False
        self.stick_lin, self.stick_ang = np.zeros(3), np.zeros(3)  # the hand stick's last setpoint
        self.cp_error_max_m = 0.0  # the Stabilizer's |CP_ref - CP_act| since the last report (flag at 0.04 m)
        self.cp_error_peak_m = 0.0  # ... since the operator started

    def say(self, msg: str) -> None:
        line = f"{self.robot.loop.snapshot.time_s:7.2f} s  {msg}"
        self.log.append(line)
        if self.progress is not None:
            self.progress(line)

    def measured(self, frame: str) -> tuple[np.ndarray, np.ndarray]:
        """(position [m], rotation) of `frame` relative to the soles' midpoint, from the encoders."""
        s = self.robot.loop.snapshot
        return frame_from_soles_midpoint(self.kin, s.base_rpy_est_rad, s.q_meas_rad, frame)

    def step(self) -> None:
        obs = self.robot.step()
        st = obs.snapshot.layers.get("st")
        if st is not None:
            self.cp_error_max_m = max(self.cp_error_max_m, st.cp_error_norm)
            self.cp_error_peak_m = max(self.cp_error_peak_m, st.cp_error_norm)
        co = obs.snapshot.layers.get("co")
        if co is not None and getattr(co, "collision", False):
            raise RuntimeError(f"the CollisionDetector holds the posture: {co.pairs}")
        op_status = obs.snapshot.layers.get("op")
        if op_status is not None and getattr(op_status, "motion_stopped", False):
            cp = "" if st is None else f": |cp error| {1e3 * st.cp_error_norm:.0f} mm at {st.flag_rose_at:.2f} s"
            raise RuntimeError(f"the EmergencyStopper stopped the motion (capture point flag{cp})")
        if obs.fallen or obs.snapshot.fault is not None:
            self.fallen = self.fallen or obs.fallen
            raise RuntimeError("the robot fell" if obs.fallen else f"fault: {obs.snapshot.fault}")

    def press(self, name: str, params: dict | None = None, timeout_s: float = 30.0):
        run_id = self.service.run_behavior(name, params or {})
        for _ in range(int(timeout_s / self.robot.loop.dt_control_s)):
            self.step()
            status = self.service.get_run(run_id)
            if status.state != "running":
                self.say(f"{name}: {status.state} ({status.message})")
                return status
        raise RuntimeError(f"{name} still running after {timeout_s} s")

    def drive(self, hand_m=None, hand_R=None, waist_z_m=None, waist_pitch_rad=None, tol_m: float = 0.003,
              tol_rad: float = math.radians(1.0), timeout_s: float = 10.0, label: str = "",
              linear_m_s: float = LINEAR_M_S, angular_rad_s: float = ANGULAR_RAD_S,
              waist_m_s: float = LINEAR_M_S, point: str = "rhand", required: bool = False) -> None:
        """Move the sticks until the hand (`point`'s frame) and the waist are where asked (None: stick left alone),
        then release them (zero setpoints). `required`: a step that timed out ends the run, with what the console
        showed as the point's limit."""
        dt = self.robot.loop.dt_control_s
        for k in range(int(timeout_s / dt)):
            done = True
            p, R = self.measured(HAND_FRAMES[point])
            lin, ang = np.zeros(3), np.zeros(3)
            if hand_m is not None:
                e = np.asarray(hand_m) - p
                done &= float(np.linalg.norm(e)) < tol_m
                lin = _capped(GAIN_1_S * e, linear_m_s)
            if hand_R is not None:
                e = rotation_vector(R, hand_R)
                done &= float(np.linalg.norm(e)) < tol_rad
                ang = _capped(GAIN_1_S * e, angular_rad_s)
            if hand_m is not None or hand_R is not None:
                lin, ang = self._ramped(lin, ang)
                self.service.put_setpoint(Setpoint(point, tuple(lin), tuple(ang)))
            if waist_z_m is not None or waist_pitch_rad is not None:
                pw, Rw = self.measured("BODY")
                vz, wy = 0.0, 0.0
                if waist_z_m is not None:
                    ez = waist_z_m - pw[2]
                    done &= abs(ez) < tol_m
                    vz = float(np.clip(GAIN_1_S * ez, -waist_m_s, waist_m_s))
                if waist_pitch_rad is not None:
                    ep = waist_pitch_rad - _pitch_rad(Rw)
                    done &= abs(ep) < tol_rad
                    wy = float(np.clip(GAIN_1_S * ep, -angular_rad_s, angular_rad_s))
                self.service.put_setpoint(Setpoint("waist", (0.0, 0.0, vz), (0.0, wy, 0.0)))
            if done:
                break
            if k % 200 == 0:
                self._trace(p, R, hand_R)
            self.step()
        limited = self.limited()  # before the sticks are released
        self.release_sticks()
        p, R = self.measured(HAND_FRAMES[point])
        off = "" if hand_m is None else f", {1e3 * np.linalg.norm(np.asarray(hand_m) - p):.1f} mm off"
        if hand_R is not None:
            off += f", {math.degrees(np.linalg.norm(rotation_vector(R, hand_R))):.1f} deg off"
        self.say(f"{label}: hand at ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m{off}{'' if done else ' (timed out)'}; "
                 f"cp error up to {1e3 * self.cp_error_max_m:.0f} mm")
        self.cp_error_max_m = 0.0
        if required and not done:
            raise RuntimeError(f"{label}: the hand stopped at ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m{off}; "
                               f"limited {limited}")

    def _trace(self, p: np.ndarray, R: np.ndarray, hand_R) -> None:
        """Once a second while driving: what the console shows (hand, waist, why a point is limited)."""
        pw, Rw = self.measured("BODY")
        rot = 0.0 if hand_R is None else math.degrees(np.linalg.norm(rotation_vector(R, hand_R)))
        self.say(f"  .. hand {np.round(p, 3)}, {rot:.1f} deg off; waist z {pw[2]:.3f} m, pitch "
                 f"{math.degrees(_pitch_rad(Rw)):.1f} deg; limited {self.limited()}; right arm (encoders) "
                 f"{np.round(np.degrees(self.robot.loop.snapshot.q_meas_rad[RARM_JOINTS])).astype(int)} deg")

    def _ramped(self, lin: np.ndarray, ang: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The hand stick moved at most STICK_RAMP_1_S of its range a second (a thumb, not a step)."""
        dt = self.robot.loop.dt_control_s
        step_lin, step_ang = STICK_RAMP_1_S * LINEAR_M_S * dt, STICK_RAMP_1_S * ANGULAR_RAD_S * dt
        self.stick_lin = self.stick_lin + np.clip(lin - self.stick_lin, -step_lin, step_lin)
        self.stick_ang = self.stick_ang + np.clip(ang - self.stick_ang, -step_ang, step_ang)
        return self.stick_lin, self.stick_ang

    def limited(self) -> dict:
        """Why each operated point did less than asked, as the console shows it."""
        st = self.robot.loop.snapshot.layers.get("op")
        return {} if st is None else {n: ps.limited for n, ps in st.points.items() if ps.limited}

    def release_sticks(self) -> None:
        for point in ("rhand", "lhand", "waist"):
            self.service.put_setpoint(Setpoint(point, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
        self.stick_lin, self.stick_ang = np.zeros(3), np.zeros(3)
        self.step()

    def wait(self, seconds: float) -> None:
        for _ in range(round(seconds / self.robot.loop.dt_control_s)):
            self.step()


def pick_up(op: Operator, obj_rel: np.ndarray, waist0: np.ndarray) -> None:
    """Gripper open, the hand forward and turned to the side grasp standing, squat, the waist pitched, down to
    the object whose centre is `obj_rel` [m, F] (grasped GRASP_ABOVE_CENTRE_M above it), grasp, lift 0.10 m."""
    R_grasp = grasp_rotation_feet(HAND_PITCH_RAD)
    in_hand = _object_in_hand_m()
    # going down, the object between the open jaws' middle (the fixed jaw would push it along the floor)
    u = -in_hand / np.linalg.norm(in_hand)  # from the fixed jaw towards the finger
    mid_open = in_hand + (OPEN_GAP_M / 2 - HALF_WIDTH_M) * u
    approach = -R_grasp[:, 2]
    op.press("release", {"hand": "rhand"})  # open the gripper
    op.drive(hand_m=np.array(VIA_M), label="hand forward (standing)")
    op.drive(hand_m=np.array(ROTATE_AT_M), hand_R=R_grasp, label="rotate (standing)")
    op.drive(hand_m=np.array(BACK_M), hand_R=R_grasp, label="back from the table's edge")
    op.drive(hand_m=np.array(SQUAT_HAND_M), hand_R=R_grasp, waist_z_m=waist0[2] - WAIST_DOWN_M,
             waist_pitch_rad=0.0, label="squat")
    op.drive(waist_pitch_rad=WAIST_PITCH_RAD, angular_rad_s=WAIST_PITCH_RATE_RAD_S, label="waist pitched")
    grasp_at = np.asarray(obj_rel) + np.array([0.0, 0.0, GRASP_ABOVE_CENTRE_M]) - R_grasp @ mid_open
    op.drive(hand_m=grasp_at - 0.10 * approach + np.array([0.0, 0.0, 0.05]), hand_R=R_grasp,
             label="above, behind the object", tol_m=0.01)
    op.drive(hand_m=grasp_at - 0.10 * approach, hand_R=R_grasp, label="pre-grasp", tol_m=0.01)
    op.drive(hand_m=grasp_at, hand_R=R_grasp, label="grasp pose", linear_m_s=0.05)
    op.wait(0.5)
    if op.press("grasp", {"hand": "rhand", "force_n": GRIP_FORCE_N}).state != "succeeded":
        raise RuntimeError("the grasp failed")
    op.drive(hand_m=grasp_at + np.array([0.0, 0.0, 0.10]), hand_R=R_grasp, label="lift")


def carry_rotation() -> np.ndarray:
    """(3, 3) the hand in F carrying: the object upright, the hand turned about the vertical (the object's yaw is
    free) where the wrist and the elbow keep a margin at standing height."""
    return rotation_z(CARRY_YAW_RAD) @ grasp_rotation_feet(HAND_PITCH_RAD)


def carried_hand_m(centre) -> np.ndarray:
    """The hand position [m, F] that carries the grasped object's centre at `centre` [m, F]."""
    return np.asarray(centre) + np.array([0.0, 0.0, GRASP_ABOVE_CENTRE_M]) - carry_rotation() @ _object_in_hand_m()


def stand_up(op: Operator, waist0: np.ndarray) -> None:
    """After the lift: the left hand out of the way of the left thigh (the torso turns with the right arm), the
    forearm turned back through UNWIND_WAYPOINTS squatting, then stand with the object at STAND_OBJECT_M."""
    R_grasp = grasp_rotation_feet(HAND_PITCH_RAD)
    pl, Rl = op.measured("larm_end")
    op.drive(hand_m=pl + np.array(LEFT_HAND_SHIFT_M), hand_R=Rl, point="lhand", label="left hand out")
    for k, (pos, ypr) in enumerate(UNWIND_WAYPOINTS):
        op.drive(hand_m=np.array(pos), hand_R=turned(ypr) @ R_grasp, label=f"unwind {k}", tol_m=0.005,
                 tol_rad=math.radians(2.0), linear_m_s=0.05, required=True)
    op.drive(hand_m=carried_hand_m(STAND_OBJECT_M), hand_R=carry_rotation(), waist_z_m=waist0[2],
             waist_pitch_rad=0.0, angular_rad_s=WAIST_PITCH_RATE_RAD_S, label="stand", tol_m=0.01, waist_m_s=0.05,
             timeout_s=12.0, required=True)


def run(progress=None, through: str = "table") -> FloorResult:
    """The task; `through="lift"` ends after the object is lifted off the floor."""
    if through not in ("lift", "table"):
        raise ValueError(f"through={through!r}: 'lift' or 'table'")
    wall0 = time.perf_counter()
    robot = LocalRobot("expo", speed=None)
    service = OperatorService(robot)
    plant = robot.plant
    stance = np.array([gen.EXPO_TABLE_NEAR_EDGE_X_M - STANDOFF_M, gen.EXPO_TABLE_CENTRE_Y_M])
    half_h = gen.UNKNOWN_OBJECT_SIZE_M[2] / 2
    top_z = gen.EXPO_TABLE_SIZE_M[2]
    object_floor = plant.place_object("unknown_object", tuple(stance + OBJECT_FLOOR_IN_STANCE_M))
    robot.run_for(SETTLE_S)
    op = Operator(robot, service, progress)
    message = ""
    lifted_m = None
    released_at = None
    try:
        op.press("approach_table", {"standoff_m": STANDOFF_M}, timeout_s=60.0)
        op.wait(1.0)
        # what the operator sees: the object where it was placed, relative to the soles' midpoint
        p0, R0 = op.measured("rarm_end")
        waist0, _ = op.measured("BODY")
        feet = 0.5 * (np.asarray(op.measured("rleg_end")[0]) + np.asarray(op.measured("lleg_end")[0]))
        del feet
        obj_rel = np.array([object_floor[0] - stance[0], object_floor[1] - stance[1], object_floor[2]])
        op.say(f"object seen at ({obj_rel[0]:.3f}, {obj_rel[1]:.3f}, {obj_rel[2]:.3f}) m from the feet centre")
        pick_up(op, obj_rel, waist0)
        lifted_m = float(plant.object_pose("unknown_object")[0][2] - object_floor[2])  # the verdict's only
        op.say(f"lift: the object {1e3 * lifted_m:.0f} mm above where it stood (simulator, for the verdict)")
        if through == "lift":
            raise _Done
        R_carry = carry_rotation()
        carried = carried_hand_m
        stand_up(op, waist0)
        op.drive(hand_m=carried(RISE_OBJECT_M), hand_R=R_carry, label="up, behind the table's edge", tol_m=0.01,
                 required=True)
        op.drive(hand_m=carried(ABOVE_EDGE_OBJECT_M), hand_R=R_carry, label="above the edge", tol_m=0.01,
                 required=True)
        place_at = carried(np.array([*OBJECT_TABLE_IN_STANCE_M, top_z + half_h]))
        op.drive(hand_m=place_at + np.array([0.0, 0.0, 0.03]), hand_R=R_carry, label="over the table",
                 required=True)
        op.drive(hand_m=place_at + np.array([0.0, 0.0, 0.005]), hand_R=R_carry, label="lowered", linear_m_s=0.03,
                 required=True)
        op.wait(0.5)
        if op.press("release", {"hand": "rhand"}).state != "succeeded":
            raise RuntimeError("the release failed")
        released_at, _ = plant.object_pose("unknown_object")  # the verdict's only
        back = place_at + np.array([0.0, 0.0, 0.005]) + 0.06 * R_carry[:, 2]
        op.drive(hand_m=back, hand_R=R_carry, label="withdraw", linear_m_s=0.05, tol_m=0.01)
        op.drive(hand_m=back + np.array([-0.05, 0.0, 0.04]),
                 hand_R=rotation_z(CARRY_YAW_RAD) @ grasp_rotation_feet(WITHDRAW_PITCH_RAD),
                 label="withdraw, hand turned up", tol_m=0.01)
        op.wait(1.0)
    except _Done:
        pass
    except Exception as exc:  # a fall, a fault, a refused setpoint: the run ends there
        message = str(exc)
    end, quat = plant.object_pose("unknown_object")
    tilt_deg = math.degrees(2.0 * math.asin(min(1.0, math.hypot(quat[1], quat[2]))))  # wxyz: axis from vertical
    moved_mm = None if released_at is None else 1e3 * float(np.linalg.norm(np.asarray(end) - released_at))
    sim_s = float(robot.loop.snapshot.time_s)
    robot.close()
    error_mm = 1e3 * (end[2] - (top_z + half_h))
    edge = gen.EXPO_TABLE_NEAR_EDGE_X_M
    inside = (edge < end[0] < edge + gen.EXPO_TABLE_SIZE_M[0]
              and abs(end[1] - gen.EXPO_TABLE_CENTRE_Y_M) < gen.EXPO_TABLE_SIZE_M[1] / 2)
    if through == "lift":
        if not message and not (lifted_m is not None and lifted_m >= LIFTED_MIN_M):
            message = f"the object was not lifted: {lifted_m} m off the floor"
    elif not message and not (inside and abs(error_mm) < ON_TABLE_TOL_MM and tilt_deg < UPRIGHT_TOL_DEG):
        message = (f"the object ended at ({end[0]:.3f}, {end[1]:.3f}, {end[2]:.3f}) m, tilted {tilt_deg:.1f} deg, "
                   "not standing on the table top")
    elif not message and not (moved_mm is not None and moved_mm < STILL_TOL_MM):
        message = f"the object moved {moved_mm} mm after the release (still in the hand?)"
    verdict = "succeeded" if not message else f"failed: {message}"
    return FloorResult(verdict, tuple(float(v) for v in end), error_mm, tilt_deg, moved_mm, lifted_m, op.fallen,
                       1e3 * op.cp_error_peak_m, sim_s, time.perf_counter() - wall0, op.log)


def main(argv) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="hrp2-console experiment floor",
                                description="[OP] Fig. 7(c): the unknown object from the floor onto the table "
                                            "by joystick, after approach_table.")
    p.add_argument("--verbose", action="store_true", help="print each step")
    p.add_argument("--through", choices=("lift", "table"), default="table",
                   help="lift: stop once the object is lifted off the floor")
    args = p.parse_args(list(argv))
    r = run(progress=(lambda m: print(m, flush=True)) if args.verbose else None, through=args.through)
    x, y, z = r.object_end_m
    lifted = "-" if r.lifted_m is None else f"{1e3 * r.lifted_m:.0f} mm"
    moved = "-" if r.moved_after_release_mm is None else f"{r.moved_after_release_mm:.1f} mm"
    print(f"floor object: {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.1f} s; lifted {lifted}; object at "
          f"({x:.3f}, {y:.3f}, {z:.3f}) m, {r.on_table_error_mm:+.1f} mm from resting on the top, tilted "
          f"{r.tilt_deg:.1f} deg, moved {moved} after the release; cp error peak {r.cp_error_peak_mm:.0f} mm")
    print(r.verdict)
    return 0 if r.succeeded else 1


if __name__ == "__main__":
    import sys

    raise SystemExit(main(sys.argv[1:]))
