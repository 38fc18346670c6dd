"""The joystick-only EXPO task of [OP] VI, Fig. 7(c): `hrp2-console experiment floor`.

"The operator operates the robot's right hand using joysticks to put the unknown bag on the table after
approaching to the table using behavior level command Approach Table." The unknown object is placed on the
floor beside the approach stance (a simulator operation, as the human would see it), `approach_table` runs,
then a scripted operator streams stick setpoints every tick through `OperatorService.put_setpoint` (the path
of WS /ws/operator) and presses the gripper buttons (`grasp`, `release`): rotate the hand while standing,
squat and pitch the waist, reach down beside the object, grasp, lift, stand, reach over the table, lower,
release, withdraw.

The operator closes the loop on what a human at the console sees: the robot's own hand pose (forward
kinematics of the encoders with the KalmanFilter attitude, relative to the soles' midpoint) and where the
object was placed. Stick speeds are a human's: at most 0.1 m/s and 20 deg/s. The simulator's pose of the
object is read only for the verdict: it rests on the table top (centre at 0.70 m + half its height), inside
the top's outline, and the robot has not fallen."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

import robot.generate as gen
from app.service import OperatorService
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint
from behaviors.servo import rotation_vector
from controller.kinematics.model import RobotKinematics, frame_from_soles_midpoint

SETTLE_S = 2.5  # [s] standing before the first command (the AutoBalancer starts in 2 s)
STANDOFF_M = 0.3  # [m] approach_table's feet centre to the table's near edge (its default)
LINEAR_M_S = 0.1  # [m/s] the fastest stick speed used (a human's)
ANGULAR_RAD_S = math.radians(20.0)  # [rad/s] likewise for rotations
STICK_RAMP_1_S = 2.0  # [1/s] the hand stick goes from rest to full deflection in 0.5 s at the fastest
GAIN_1_S = 2.0  # [1/s] stick deflection per metre (or radian) of error: the operator slows near the target
#: The object on the floor, relative to the stance (feet centre after approach_table, F axes) [m]: ahead of the
#: right foot, in reach of the squatting robot's right hand.
OBJECT_FLOOR_IN_STANCE_M = (0.24, -0.33)
#: Where the operator puts it on the table top, relative to the stance [m]: 0.15 m in from the near edge.
OBJECT_TABLE_IN_STANCE_M = (STANDOFF_M + 0.15, -0.25)
VIA_M = (0.30, -0.30, 0.80)  # [m] the hand first goes forward and up here, its orientation kept (as take_can)
ROTATE_AT_M = (0.36, -0.28, 0.82)  # [m] ... then turns to the grasp orientation here (take_can's pre-grasp)
BACK_M = (0.18, -0.30, 0.82)  # [m] ... and back: going down, the fingers clear the table top's near edge
SQUAT_HAND_M = (0.18, -0.34, 0.44)  # [m] the hand goes down to here while the robot squats
#: The hand pitched this far down (the can's grasp on the table is 30 deg): with the arm stretched down to the
#: floor the hand lies nearly along the forearm; the same orientation puts the object down upright.
HAND_PITCH_RAD = math.radians(65.0)
UP_BEFORE_TABLE_M = (0.20, -0.28, 0.92)  # [m] the held object lifted clear of the table top before going over it
GRASP_ABOVE_CENTRE_M = 0.07  # [m] the jaws close this far above the object's middle
WAIST_DOWN_M = 0.26  # [m] the squat
WAIST_PITCH_RAD = math.radians(25.0)  # the waist pitched forward while squatting
WAIST_PITCH_RATE_RAD_S = math.radians(10.0)  # ... slowly: 20 deg/s while squatting set the capture-point flag
OPEN_GAP_M = 0.10  # [m] between the fully open jaws (robot/hrp2/README.md)
LIFTED_MIN_M = 0.05  # [m] the lift (0.10 m of the hand) counts when the object rose this much
HALF_WIDTH_M = gen.UNKNOWN_OBJECT_SIZE_M[1] / 2  # across the jaws


def grasp_rotation_feet(pitch_rad: float) -> np.ndarray:
    """(3, 3) the hand in F for a side grasp pitched `pitch_rad` down: fingers along the approach, the jaws
    closing along y (behaviors.hand_geometry's grasp of the can, there at 30 deg)."""
    approach = np.array([math.cos(pitch_rad), 0.0, -math.sin(pitch_rad)])
    z_hand = -approach
    x_hand = np.array([0.0, 1.0, 0.0])
    return np.column_stack([x_hand, np.cross(z_hand, x_hand), z_hand])


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
    lifted_m: float | None  # how far the grasp lifted the object off the floor (None: not got that far)
    fallen: bool
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
              waist_m_s: float = LINEAR_M_S) -> None:
        """Move the sticks until the hand (rarm_end) and the waist are where asked (None: stick left alone),
        then release them (zero setpoints)."""
        dt = self.robot.loop.dt_control_s
        for k in range(int(timeout_s / dt)):
            done = True
            p, R = self.measured("rarm_end")
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
                self.service.put_setpoint(Setpoint("rhand", tuple(lin), tuple(ang)))
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
        self.release_sticks()
        p, R = self.measured("rarm_end")
        off = "" if hand_m is None else f", {1e3 * np.linalg.norm(np.asarray(hand_m) - p):.1f} mm off"
        if hand_R is not None:
            off += f", {math.degrees(np.linalg.norm(rotation_vector(R, hand_R))):.1f} deg off"
        self.say(f"{label}: hand at ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m{off}{'' if done else ' (timed out)'}; "
                 f"cp error up to {1e3 * self.cp_error_max_m:.0f} mm")
        self.cp_error_max_m = 0.0

    def _trace(self, p: np.ndarray, R: np.ndarray, hand_R) -> None:
        """Once a second while driving: what the console shows (hand, waist, why a point is limited)."""
        pw, Rw = self.measured("BODY")
        rot = 0.0 if hand_R is None else math.degrees(np.linalg.norm(rotation_vector(R, hand_R)))
        self.say(f"  .. hand {np.round(p, 3)}, {rot:.1f} deg off; waist z {pw[2]:.3f} m, pitch "
                 f"{math.degrees(_pitch_rad(Rw)):.1f} deg; limited {self.limited()}")

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
        for point in ("rhand", "waist"):
            self.service.put_setpoint(Setpoint(point, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
        self.stick_lin, self.stick_ang = np.zeros(3), np.zeros(3)
        self.step()

    def wait(self, seconds: float) -> None:
        for _ in range(round(seconds / self.robot.loop.dt_control_s)):
            self.step()


def run(progress=None, through: str = "table") -> FloorResult:
    """The task; `through="lift"` ends after the object is lifted off the floor (the part that works so far:
    standing up with it sets the capture-point flag, see the README)."""
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
        R_grasp = grasp_rotation_feet(HAND_PITCH_RAD)
        in_hand = _object_in_hand_m()

        def hand_for(centre: np.ndarray, offset=in_hand) -> np.ndarray:
            return centre + np.array([0.0, 0.0, GRASP_ABOVE_CENTRE_M]) - R_grasp @ offset

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
        grasp_at = hand_for(obj_rel, mid_open)
        op.drive(hand_m=grasp_at - 0.10 * approach + np.array([0.0, 0.0, 0.05]), hand_R=R_grasp,
                 label="above, behind the object", tol_m=0.01)
        op.drive(hand_m=grasp_at - 0.10 * approach, hand_R=R_grasp, label="pre-grasp", tol_m=0.01)
        op.drive(hand_m=grasp_at, hand_R=R_grasp, label="grasp pose", linear_m_s=0.05)
        op.wait(0.5)
        op.press("grasp", {"hand": "rhand"})
        op.drive(hand_m=grasp_at + np.array([0.0, 0.0, 0.10]), hand_R=R_grasp, label="lift")
        lifted_m = float(plant.object_pose("unknown_object")[0][2] - object_floor[2])  # the verdict's only
        op.say(f"lift: the object {1e3 * lifted_m:.0f} mm above where it stood (simulator, for the verdict)")
        if through == "lift":
            raise _Done
        # standing up: the squat's path backwards (elsewhere the wrist meets its limits holding the pitch)
        op.drive(hand_m=np.array(BACK_M), hand_R=R_grasp, waist_z_m=waist0[2], waist_pitch_rad=0.0,
                 angular_rad_s=WAIST_PITCH_RATE_RAD_S, label="stand", tol_m=0.01, waist_m_s=0.05)
        table_rel = np.array([*OBJECT_TABLE_IN_STANCE_M, top_z + half_h])
        place_at = hand_for(table_rel)
        op.drive(hand_m=np.array(UP_BEFORE_TABLE_M), hand_R=R_grasp, label="up, before the table", tol_m=0.01)
        op.drive(hand_m=place_at + np.array([0.0, 0.0, 0.05]), hand_R=R_grasp, label="over the table")
        op.drive(hand_m=place_at + np.array([0.0, 0.0, 0.005]), hand_R=R_grasp, label="lowered")
        op.press("release", {"hand": "rhand"})
        op.drive(hand_m=place_at - 0.10 * approach, hand_R=R_grasp, label="withdraw")
        op.wait(1.0)
    except _Done:
        pass
    except Exception as exc:  # a fall, a fault, a refused setpoint: the run ends there
        message = str(exc)
    end, _ = plant.object_pose("unknown_object")
    sim_s = float(robot.loop.snapshot.time_s)
    robot.close()
    error_mm = 1e3 * (end[2] - (top_z + half_h))
    edge = gen.EXPO_TABLE_NEAR_EDGE_X_M
    inside = (edge < end[0] < edge + gen.EXPO_TABLE_SIZE_M[0]
              and abs(end[1] - gen.EXPO_TABLE_CENTRE_Y_M) < gen.EXPO_TABLE_SIZE_M[1] / 2)
    if through == "lift":
        if not message and not (lifted_m is not None and lifted_m >= LIFTED_MIN_M):
            message = f"the object was not lifted: {lifted_m} m off the floor"
    elif not message and not (inside and abs(error_mm) < 5.0):
        message = f"the object ended at ({end[0]:.3f}, {end[1]:.3f}, {end[2]:.3f}) m, not on the table top"
    verdict = "succeeded" if not message else f"failed: {message}"
    return FloorResult(verdict, tuple(float(v) for v in end), error_mm, lifted_m, op.fallen, sim_s,
                       time.perf_counter() - wall0, op.log)


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
    print(f"floor object: {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.1f} s; lifted {lifted}; object at "
          f"({x:.3f}, {y:.3f}, {z:.3f}) m, {r.on_table_error_mm:+.1f} mm from resting on the top")
    print(r.verdict)
    return 0 if r.succeeded else 1


if __name__ == "__main__":
    import sys

    raise SystemExit(main(sys.argv[1:]))
