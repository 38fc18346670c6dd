"""`take_can` ([OP] VI): locate the can if it is not located, judge from the support polygon whether it is
within the right hand's reach ([OP] IV) and walk if not (to where the head can see it, locate it again, then
to the grasping stance), open, pre-grasp, grasp, lift; the grasp is checked from the gripper's angle and the
wrist force sensor, and the run fails saying so when the can was missed or slipped.

The stance is chosen from the located can and the table's known near edge ([OP] VI: the table's place is
known): the can as near the body as the arm likes it, but the feet no nearer the edge than the hands and the
hips allow; a can far in from the edge is taken farther out in front. The free (left) arm is tucked back
before the walk, so that it hangs behind the table's edge whatever the stance and the heading."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.approach_table import TABLE_CENTRE_Y_M, TABLE_NEAR_EDGE_X_M
from behaviors.base import BehaviorParams, Context
from behaviors.composite import Composite, Plan, StepFailed, Wait
from behaviors.grasp import Grasp, GraspParams
from behaviors.gripper import gripper_joint
from behaviors.hand_geometry import (
    PRE_GRASP_BACK_M,
    approach_feet,
    can_from_hand_point,
    grasp_rotation_feet,
    hand_point_for_can,
)
from behaviors.locate_can import LocateCan
from behaviors.perception.models import CAN, HELD, NOT_ON_THE_TABLE
from behaviors.reach import Reach, reach_pose
from behaviors.release import Release, ReleaseParams
from behaviors.servo import rot_z
from behaviors.table_model import KnownTable
from behaviors.walk_to import WalkTo, WalkToParams
from controller.core.constants import GRAVITY_M_S2
from controller.walking.footsteps import FootstepParams

CAN_MASS_KG = 0.33  # a full 300 ml can (robot/hrp2/README.md)
#: The can where the right hand takes it best, relative to the support polygon's centre (the feet frame F) [m]:
#: forward of the toes, on the right shoulder's line, at the height of the 0.70 m table (the grasp check).
GRASP_CAN_FEET_M = (0.43, -0.22)
#: The open hand closes this far past where the can would sit centred in it [m], along its approach: the palm
#: seats the can (measured, `tests/scenarios/test_expo_carry.py`'s 1.4 m carry: slip 5.6 mm at 0, 5.0 at 5 mm,
#: 3.5 at 10 mm, 2.9 at 15 mm, 2.7 at 20 mm). Before leg odometry the walk to the stance ended about 10 mm
#: nearer the can than the plan knew, and every grasp went that much past it unplanned (slip 3.2 mm).
GRASP_PAST_CENTRE_M = 0.010
#: The feet centre stays this far from the table's near edge [m]: nearer, the open right hand rising from
#: where it hangs (0.11 m ahead of the feet) met the edge from below (measured: feet 0.157 m from the edge,
#: the can 0.29 m in, the reach stopped 148 mm short), and the hips (0.70 m high, the table top's height)
#: come close to it. Measured clear: 0.28 m (the can 0.15 m in).
FEET_TO_EDGE_MIN_M = 0.22
#: The farthest forward the right hand takes the can (F x) [m], for a can far in from the edge.
GRASP_CAN_X_MAX_M = 0.52
#: The reachable box around it [m]: closer or farther, the 30 deg hand would meet the table or its limits (a can
#: taken 0.57 m out was held; 0.56 m is the farthest a stance kept off a table leg asks: a can at U 0.60, V 0.30).
REACH_BOX_M = ((0.38, GRASP_CAN_X_MAX_M + 0.04), (-0.28, -0.16))
#: The can's F y [m] the stance may choose instead of GRASP_CAN_FEET_M's to keep the legs clear of the table's
#: legs: the reach box's y less 1 cm each side.
CAN_Y_FEET_RANGE_M = (REACH_BOX_M[1][0] + 0.01, REACH_BOX_M[1][1] - 0.01)
#: [m] a foot's centre from the feet centre, across (the gait's leg_offset_y_m)
FOOT_OFFSET_Y_M = FootstepParams().leg_offset_y_m
#: [m] how far the leg reaches across from its foot's centre line: outward, the knee's capsule (0.092 m) and the
#: sole (0.079 m); inward, the sole (0.059 m) (robot/hrp2 model)
LEG_OUT_M, LEG_IN_M = 0.095, 0.06
#: [m] kept between the robot's legs and a table leg beside them, across (walking tolerance and sway)
LEG_CLEARANCE_M = 0.03
#: [m] the feet centre stays this far back from the face of a table leg that stands in line with a foot: the
#: knee's front is 0.20 m ahead of its foot standing and 0.26 m with the foot lifted 5 cm (measured in
#: simulation); LLEG_LINK3 met the leg at about 0.25 m when the aligning step lifted the left foot in line with it
#: (seed 2005, trial 10: the robot fell). 2 cm of margin; more puts a can 0.30 m in beyond the reach box.
KNEE_TO_LEG_MIN_M = 0.28
#: Located from farther than this [m], the can is located again from LOOK_BACK_M behind the grasping stance
#: (the head cannot pitch down 57 deg to see it from the stance, and a long walk adds odometry error).
RELOCATE_FROM_M = 1.3
LOOK_BACK_M = 0.5
#: At the stance the open right hand first rises where it hangs (0.54 m high, below the table top, 0.11 m
#: ahead of the feet) to READY, keeping its orientation, then goes forward over the table to VIA: straight
#: from where it hangs to the pre-grasp its jaw caught the table's edge. (Raised before the walk instead,
#: the wrist met the chest swaying with the gait: the hand is held in the feet frame.)
READY_FEET_M = (0.12, -0.33, 0.78)
VIA_FEET_M = (0.30, -0.30, 0.80)
#: The free left hand is tucked back beside the hip (F) [m] before any walk: hanging 0.11 m ahead of the
#: feet at the table top's height, 0.36 m out to the side, it met the table's edge reaching from a close
#: stance, and on the walk to the box along the table (facing along the edge, the left hand on the table's
#: side) it caught the edge and the robot fell (two trials of seed 1, t = 99 s and 104 s). 0.38 m out, not
#: 0.35: at 0.35 the upper arm (LARM_LINK3) sat inside the CollisionDetector's 5 mm margin of the chest, and
#: the shoulder's 2 deg of roll holding the hand while the head pitched down to relocate the box made it
#: hold the whole posture, the gaze stuck at 24 of 40 deg (the can 0.15 m in on the table's middle).
LHAND_TUCK_FEET_M = (-0.02, 0.38, 0.60)
#: The wrist force is read this long after the hand stops [s], averaged over WRIST_MEAN_S [s].
WRIST_SETTLE_S = 0.3
WRIST_MEAN_S = 0.2
#: After the check the robot steps back this far [m] with the can held: at the grasping stance the feet
#: centre is 0.28 m from the table's edge, and turning there the left palm met the table top (the robot fell).
#: 0.3 m cleared the turn, but walking on to the box along the table (the left wrist 0.33 m beside BODY, at
#: the table top's height, BODY swaying 0.1 m) the palm met the edge again.
STEP_BACK_M = 0.5


@dataclass(frozen=True)
class TakeCanParams(BehaviorParams):
    lift_m: float = field(default=0.08, metadata={"unit": "m", "min": 0.02, "max": 0.2, "doc": "lift after the grasp"})
    force_n: float = field(default=14.0, metadata={"unit": "N", "min": 5.0, "max": 14.0, "doc": "fingertip force"})
    speed_m_s: float = field(default=0.1, metadata={"unit": "m/s", "min": 0.02, "max": 0.3, "doc": "hand speed"})
    min_load_ratio: float = field(default=0.5, metadata={"unit": "-", "min": 0.1, "max": 1.0,
                                                         "doc": "the wrist must carry this share of the can's "
                                                                "weight after the lift"})
    slip_deg: float = field(default=3.0, metadata={"unit": "deg", "min": 0.5, "max": 20.0,
                                                   "doc": "the jaw closing further than this after the grasp "
                                                          "means the can slipped"})
    table_edge_x_m: float = field(default=TABLE_NEAR_EDGE_X_M, metadata={
        "unit": "m", "min": -20.0, "max": 20.0,
        "doc": "the table's near edge, world x (its known place; the near side faces -x)"})
    table_centre_y_m: float = field(default=TABLE_CENTRE_Y_M, metadata={
        "unit": "m", "min": -20.0, "max": 20.0, "doc": "the table's middle along its near edge, world y (known)"})


def can_in_feet(view, can_world) -> np.ndarray:
    d = np.asarray(can_world, dtype=float) - np.asarray(view.feet_p_world_m, dtype=float)
    return rot_z(view.feet_yaw_rad).T @ d


def grasp_can_x_feet(can_from_edge_m: float) -> float:
    """How far ahead of the feet centre (F x) [m] to take a can `can_from_edge_m` in from the table's edge:
    GRASP_CAN_FEET_M's x, or farther out so the feet stay FEET_TO_EDGE_MIN_M from the edge, at most
    GRASP_CAN_X_MAX_M."""
    return float(min(max(GRASP_CAN_FEET_M[0], can_from_edge_m + FEET_TO_EDGE_MIN_M), GRASP_CAN_X_MAX_M))


def stance_for(can_world, yaw_rad: float, x_feet_m: float = GRASP_CAN_FEET_M[0],
               back_m: float = 0.0, y_feet_m: float = GRASP_CAN_FEET_M[1]) -> tuple[float, float]:
    """The feet frame's place (world x, y) that puts the can at (x_feet_m + back_m, y_feet_m) in F."""
    offset = rot_z(yaw_rad) @ np.array([x_feet_m + back_m, y_feet_m, 0.0])
    return float(can_world[0] - offset[0]), float(can_world[1] - offset[1])


def legs_clear_of_table_legs(feet_y_m: float, table: KnownTable) -> bool:
    """Both of the robot's legs (feet centre at world y `feet_y_m`, facing the table) LEG_CLEARANCE_M or more
    across from each of the table's near legs."""
    bands = ((feet_y_m + FOOT_OFFSET_Y_M - LEG_IN_M, feet_y_m + FOOT_OFFSET_Y_M + LEG_OUT_M),  # left leg
             (feet_y_m - FOOT_OFFSET_Y_M - LEG_OUT_M, feet_y_m - FOOT_OFFSET_Y_M + LEG_IN_M))  # right leg
    c = LEG_CLEARANCE_M
    legs = table.near_leg_spans_y_m()
    return all(hi + c <= lo_leg or lo - c >= hi_leg for lo, hi in bands for lo_leg, hi_leg in legs)


def grasp_beside_legs(can_world, yaw_rad: float, x_feet_m: float, table: KnownTable) -> tuple[float, float]:
    """Where in F (x, y) [m] to take the can so that the knees keep off the table's legs: (x_feet_m,
    GRASP_CAN_FEET_M's y) when the feet stand KNEE_TO_LEG_MIN_M or more back from the legs' faces or no leg is
    beside them; else the nearest y in CAN_Y_FEET_RANGE_M that keeps the legs across from the table's legs; else
    (no such y: a can near a table leg, a little in from the end) x farther out, the feet KNEE_TO_LEG_MIN_M back."""
    y0 = GRASP_CAN_FEET_M[1]
    feet_x, feet_y = stance_for(can_world, yaw_rad, x_feet_m, y_feet_m=y0)
    if feet_x <= table.near_leg_face_x_m - KNEE_TO_LEG_MIN_M or legs_clear_of_table_legs(feet_y, table):
        return x_feet_m, y0
    lo, hi = CAN_Y_FEET_RANGE_M
    for y in sorted(np.linspace(lo, hi, round((hi - lo) / 0.005) + 1).tolist(), key=lambda v: abs(v - y0)):
        if legs_clear_of_table_legs(stance_for(can_world, yaw_rad, x_feet_m, y_feet_m=y)[1], table):
            return x_feet_m, y
    return max(x_feet_m, x_feet_m + feet_x - (table.near_leg_face_x_m - KNEE_TO_LEG_MIN_M)), y0


def within_reach(can_feet, can_from_edge_m: float | None = None) -> bool:
    """The can inside the reach box, and (given how far in from the table's edge it is) the feet no nearer the
    edge than FEET_TO_EDGE_MIN_M (2 cm of walking tolerance)."""
    (x0, x1), (y0, y1) = REACH_BOX_M
    in_box = x0 <= can_feet[0] <= x1 and y0 <= can_feet[1] <= y1
    return in_box and (can_from_edge_m is None or can_feet[0] - can_from_edge_m >= FEET_TO_EDGE_MIN_M - 0.02)


class TakeCan(Composite):
    name = "take_can"
    Params = TakeCanParams
    summary = "Locate the can if needed, walk within reach, grasp it with the right hand and lift it"
    phases = ("locate", "tuck", "walk", "relocate", "walk", "open", "pre-grasp", "grasp", "close", "lift",
              "check", "step back")
    remaining_estimate_s = 40.0

    def points(self) -> tuple[str, ...]:
        return ("head", "walk", "rhand", "lhand")

    def resources(self) -> tuple[str, ...]:
        return (*self.points(), "rhand.gripper")

    def _reach(self, p_feet, R_feet=None, hand: str = "rhand") -> Reach:
        return reach_pose(hand, p_feet, R_feet, self.params.speed_m_s)

    def _mean_wrist_force(self, commands):
        """(3,) the right wrist's force [N, sensor frame] averaged over WRIST_MEAN_S after WRIST_SETTLE_S (a plan
        step: `f = yield from ...`): one tick's reading swings by newtons with the arm's servo vibration."""
        yield Wait(WRIST_SETTLE_S)
        samples = []
        for _ in range(max(1, round(WRIST_MEAN_S / self.ctx.dt_s))):
            yield Wait(self.ctx.dt_s)
            samples.append(np.asarray(commands.wrench("rhsensor")[:3], dtype=float))
        return np.mean(samples, axis=0)

    def _locate_near(self, can_world) -> LocateCan:
        return LocateCan(LocateCan.Params(x_m=float(can_world[0]), y_m=float(can_world[1]),
                                          z_m=float(can_world[2]), views=1))

    def plan(self, ctx: Context) -> Plan:
        p = self.params
        commands = ctx.commands
        self.set_phase("locate")
        can = commands.recalled("can")
        if can is None or can.get("status") in NOT_ON_THE_TABLE:  # held, or thrown: where is it now?
            self.require((yield LocateCan()))
            can = commands.recalled("can")
        can_world = np.array(can["position_m"])
        self.set_phase("tuck")
        self.require((yield self._reach(np.array(LHAND_TUCK_FEET_M), hand="lhand")))
        view = self.view
        yaw = view.feet_yaw_rad
        can_f = can_in_feet(view, can_world)
        self.result["can_feet_m"] = [round(float(v), 4) for v in can_f]
        edge_x_m = p.table_edge_x_m
        table = KnownTable(near_edge_x_m=edge_x_m, centre_y_m=p.table_centre_y_m)
        in_from_edge_m = float(can_world[0]) - edge_x_m
        x_grasp = grasp_can_x_feet(in_from_edge_m)
        self.result["grasp_can_x_feet_m"] = round(x_grasp, 4)
        if not within_reach(can_f, in_from_edge_m):
            if can.get("from_m", 0.0) > RELOCATE_FROM_M:
                self.set_phase("walk")
                x, y = stance_for(can_world, yaw, x_grasp, LOOK_BACK_M)
                self.require((yield WalkTo(WalkToParams(x_m=x, y_m=y, theta_deg=math.degrees(yaw)))))
                self.set_phase("relocate")
                self.require((yield self._locate_near(can_world)))
                relocated = np.array(commands.recalled("can")["position_m"])
                # the can has not moved: where it is seen now against where it was seen from the start is what
                # the walk's odometry got wrong, and the table's known edge is taken to be off by as much (leg
                # odometry: a few mm; with the gait plan's odometry it was 55 mm after a 1.8 m walk, and the
                # feet ended 0.17 m from the edge, not 0.22, and the hand met it)
                edge_x_m += float(relocated[0] - can_world[0])
                table = table.shifted(float(relocated[0] - can_world[0]), float(relocated[1] - can_world[1]))
                can_world = relocated
                in_from_edge_m = float(can_world[0]) - edge_x_m
                x_grasp = grasp_can_x_feet(in_from_edge_m)
            self.set_phase("walk")
            x_grasp, y_grasp = grasp_beside_legs(can_world, yaw, x_grasp, table)
            self.result.update(grasp_can_x_feet_m=round(x_grasp, 4), grasp_can_y_feet_m=round(y_grasp, 4))
            if x_grasp > REACH_BOX_M[0][1]:
                raise StepFailed(f"the can stands in line with a leg of the table, {in_from_edge_m:.2f} m in from "
                                 f"the edge: from where the knees keep {KNEE_TO_LEG_MIN_M} m off the leg it is "
                                 f"{x_grasp:.2f} m ahead, beyond the reach box {REACH_BOX_M}")
            x, y = stance_for(can_world, yaw, x_grasp, y_feet_m=y_grasp)
            self.require((yield WalkTo(WalkToParams(x_m=x, y_m=y, theta_deg=math.degrees(yaw),
                                                    tolerance_m=0.02))))
            yield Wait(0.5)
        view = self.view
        can_f = can_in_feet(view, can_world)
        self.result["can_feet_m"] = [round(float(v), 4) for v in can_f]
        if not within_reach(can_f, in_from_edge_m):
            raise StepFailed(f"the can is at ({can_f[0]:.3f}, {can_f[1]:.3f}) m of the feet after the walk, "
                             f"outside the reach box {REACH_BOX_M}")
        R = grasp_rotation_feet()
        grasp_f = hand_point_for_can(can_f, R) + GRASP_PAST_CENTRE_M * approach_feet()
        pre_f = grasp_f - PRE_GRASP_BACK_M * approach_feet()
        self.set_phase("open")
        self.require((yield Release(ReleaseParams(hand="rhand", time_s=0.5))))
        self.set_phase("pre-grasp")
        self.require((yield self._reach(np.array(READY_FEET_M))))
        self.require((yield self._reach(np.array(VIA_FEET_M))))
        self.require((yield self._reach(pre_f, R)))
        # the wrist's reference while the open hand is still, in the grasp orientation, touching nothing (on the
        # can, the closing approach pushes it: 13 mm and up to 15 N measured, a reference taken there read a
        # held can as 0.40 N once)
        unloaded_f = yield from self._mean_wrist_force(commands)
        self.set_phase("grasp")
        self.require((yield self._reach(grasp_f, R)))
        self.set_phase("close")
        grasp = yield Grasp(GraspParams(hand="rhand", force_n=p.force_n))
        if not grasp.outcome[0]:
            raise StepFailed(f"the can was missed: {grasp.outcome[1]}")
        jaw_grasped = commands.joint(gripper_joint("rhand")).q_meas_rad
        self.set_phase("lift")
        self.require((yield self._reach(grasp_f + np.array([0.0, 0.0, p.lift_m]))))
        self.set_phase("check")
        load_n = float(np.linalg.norm((yield from self._mean_wrist_force(commands)) - unloaded_f))
        jaw = commands.joint(gripper_joint("rhand"))
        closed_more_deg = math.degrees(jaw.q_meas_rad - jaw_grasped)
        weight_n = CAN_MASS_KG * GRAVITY_M_S2
        self.result.update(wrist_load_n=round(load_n, 3), jaw_deg=round(math.degrees(jaw.q_meas_rad), 3),
                           jaw_closed_after_grasp_deg=round(closed_more_deg, 3))
        if closed_more_deg > p.slip_deg or jaw.upper_rad - jaw.q_meas_rad < math.radians(2.0):
            raise StepFailed(f"the can slipped: the jaw closed {closed_more_deg:.1f} deg further after the grasp")
        if load_n < p.min_load_ratio * weight_n:
            raise StepFailed(f"the can slipped or was missed: the wrist carries {load_n:.2f} N after the lift, "
                             f"less than {p.min_load_ratio:.0%} of the can's {weight_n:.2f} N")
        self.set_phase("step back")
        view = self.view
        yaw = view.feet_yaw_rad
        feet = np.asarray(view.feet_p_world_m, dtype=float)
        self.require((yield WalkTo(WalkToParams(x_m=float(feet[0] - STEP_BACK_M * math.cos(yaw)),
                                                y_m=float(feet[1] - STEP_BACK_M * math.sin(yaw)),
                                                theta_deg=math.degrees(yaw)))))
        # the can is in the hand now: its recognition on the table is out of date (no pop-up to confirm it)
        hand = self.view.points["rhand"]
        commands.remember("can", {**can, "status": HELD, "position_m": [
            round(float(v), 5) for v in can_from_hand_point(hand.p_world_m, hand.R_world_point)]})
        return (f"holding the can: {load_n:.2f} N at the wrist (the can weighs {weight_n:.2f} N), "
                f"jaw at {math.degrees(jaw.q_meas_rad):.1f} deg ({CAN.diameter_m * 1e3:.0f} mm can)")
