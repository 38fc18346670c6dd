"""`open_door` ([OP] VI, Fig. 8): locate the fridge door's handle if it is not located, grasp it with the right
hand, pull the door open along its arc about the hinge (the hinge found from the handle and the door's turn as
seen, and the fridge's known shape), then hold it open for `hold_s` while the other hand works (Eq. 5: the
operator's stick on the left hand adds in the same ticks)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

import robot.generate as gen
from behaviors.base import BehaviorParams, Context
from behaviors.composite import Composite, Plan, StepFailed, Wait
from behaviors.follow_arc import FollowArc, FollowArcParams
from behaviors.grasp import Grasp, GraspParams
from behaviors.locate_handle import LocateHandle
from behaviors.perception.locate_fridge import FRIDGE, hinge_from_handle_xy
from behaviors.reach import Reach, reach_pose
from behaviors.release import Release, ReleaseParams
from behaviors.servo import rot_z

#: The open hand rises where it hangs, goes forward beside the body, then to the pre-grasp (take_can's path to
#: the can: straight from READY the wrist met the chest) [m, F].
READY_FEET_M = (0.12, -0.33, 0.78)
VIA_FEET_M = (0.30, -0.30, 0.80)
PRE_GRASP_BACK_M = 0.10  # [m] back along the approach from the grasp
#: [m] the bar sits this far past the 85 mm grasp centre along the approach when grasped (toward the palm)
GRASP_PAST_CENTRE_M = 0.01
#: [m] the hand may end this far from the arc's end: the held door pulls the hand back, and near 40 deg the right
#: arm reaches its limit (the hand turned 60 deg toward the body's middle): measured 16-39 mm
ARC_TOLERANCE_M = 0.05
GRASP_BELOW_TOP_M = 0.15  # [m] the hand takes the bar this far below its top (the located point): its middle


#: [deg] the hand takes the bar turned this far from the door's normal (pointing left, the wrist to the bar's
#: right): straight on, the wrist met the chest at the pre-grasp (the handle 0.2 m right of the body's middle)
GRASP_YAW_FROM_DOOR_DEG = 10.0


#: [deg] the hand's pitch on the bar: level, the pads lie along the bar (pitched 30 deg as for the can, a 30 mm
#: bar slipped out between them when pulled)
HAND_PITCH_DEG = 30.0


def grasp_rotation_feet(door_yaw_feet_rad: float) -> np.ndarray:
    """(3, 3) the right hand on the handle in F: fingers along the door's normal (into the fridge) turned
    GRASP_YAW_FROM_DOOR_DEG and pitched HAND_PITCH_DEG down, the jaws closing across the bar."""
    a = math.radians(HAND_PITCH_DEG)
    approach = np.array([math.cos(a), 0.0, -math.sin(a)])
    z_hand = -approach
    x_hand = np.array([0.0, 1.0, 0.0])
    R_door = np.column_stack([x_hand, np.cross(z_hand, x_hand), z_hand])
    return rot_z(door_yaw_feet_rad + math.radians(GRASP_YAW_FROM_DOOR_DEG)) @ R_door


def _bar_in_hand_m() -> np.ndarray:
    """(3,) the held bar's axis relative to rarm_end in the hand frame (against the fixed jaw) [m]."""
    params = gen.load_parameters()
    c_85, _ = gen.grasp_centre(params, "RARM")
    c_bar, _ = gen.grasp_centre(params, "RARM", FRIDGE.handle_radius_m)
    return np.array(c_bar) - np.array(c_85)


BAR_IN_HAND_M = _bar_in_hand_m()


def to_feet(view, p_world) -> np.ndarray:
    """(3,) a world point [m] in the feet frame F."""
    d = np.asarray(p_world, dtype=float) - np.asarray(view.feet_p_world_m, dtype=float)
    return rot_z(view.feet_yaw_rad).T @ d


@dataclass(frozen=True)
class OpenDoorParams(BehaviorParams):
    open_deg: float = field(default=40.0, metadata={"unit": "deg", "min": 10.0, "max": 80.0,
                                                    "doc": "how far to open the door"})
    speed_deg_s: float = field(default=10.0, metadata={"unit": "deg/s", "min": 2.0, "max": 30.0,
                                                       "doc": "the door's largest opening rate"})
    hold_s: float = field(default=0.0, metadata={"unit": "s", "min": 0.0, "max": 60.0,
                                                 "doc": "hold the door open this long before ending (the hand "
                                                        "stays on the handle afterwards too)"})
    force_n: float = field(default=14.0, metadata={"unit": "N", "min": 5.0, "max": 14.0, "doc": "fingertip force"})
    speed_m_s: float = field(default=0.1, metadata={"unit": "m/s", "min": 0.02, "max": 0.3, "doc": "hand speed"})
    locate: bool = field(default=True, metadata={"unit": "-", "doc": "locate the handle if it is not located "
                                                 "(claims the head); false: a located handle is required and the "
                                                 "head stays free for other behaviours meanwhile"})


class OpenDoor(Composite):
    name = "open_door"
    Params = OpenDoorParams
    summary = "Locate the fridge's handle if needed, grasp it with the right hand, pull the door open along its arc"
    phases = ("locate", "open", "ready", "pre-grasp", "grasp", "close", "pull", "hold")
    remaining_estimate_s = 30.0

    def points(self) -> tuple[str, ...]:
        return ("head", "walk", "rhand") if self.params.locate else ("rhand",)

    def resources(self) -> tuple[str, ...]:
        return (*self.points(), "rhand.gripper")

    def _reach(self, p_feet, R_feet=None) -> Reach:
        return reach_pose("rhand", p_feet, R_feet, self.params.speed_m_s)

    def plan(self, ctx: Context) -> Plan:
        p = self.params
        commands = ctx.commands
        self.set_phase("locate")
        handle = commands.recalled("fridge_handle")
        if handle is None:
            if not p.locate:
                raise StepFailed("no located handle: run locate_handle first, or set locate")
            self.require((yield LocateHandle()))
            handle = commands.recalled("fridge_handle")
        view = self.view
        handle_w = np.array(handle["position_m"], dtype=float) - np.array([0.0, 0.0, GRASP_BELOW_TOP_M])
        door_yaw_w = math.radians(handle["yaw_deg"])
        hinge_w = hinge_from_handle_xy(handle_w[:2], door_yaw_w)
        handle_f = to_feet(view, handle_w)
        hinge_f = to_feet(view, [*hinge_w, 0.0])
        yaw_f = door_yaw_w - view.feet_yaw_rad
        R = grasp_rotation_feet(yaw_f)
        approach = -R[:, 2]
        grasp_f = handle_f - R @ BAR_IN_HAND_M + GRASP_PAST_CENTRE_M * approach
        pre_f = grasp_f - PRE_GRASP_BACK_M * approach
        self.result.update(handle_feet_m=[round(float(v), 4) for v in handle_f],
                           hinge_feet_m=[round(float(v), 4) for v in hinge_f[:2]],
                           door_yaw_feet_deg=round(math.degrees(yaw_f), 2),
                           pre_grasp_feet_m=[round(float(v), 4) for v in pre_f])
        self.set_phase("open")
        self.require((yield Release(ReleaseParams(hand="rhand", time_s=0.5))))
        self.set_phase("ready")
        self.require((yield self._reach(np.array(READY_FEET_M))))
        self.require((yield self._reach(np.array(VIA_FEET_M))))
        self.set_phase("pre-grasp")
        self.require((yield self._reach(pre_f, R)))
        self.set_phase("grasp")
        self.require((yield self._reach(grasp_f, R)))
        self.set_phase("close")
        grasp = yield Grasp(GraspParams(hand="rhand", force_n=p.force_n))
        if not grasp.outcome[0]:
            raise StepFailed(f"the handle was missed: {grasp.outcome[1]}")
        self.set_phase("pull")
        self.require((yield FollowArc(FollowArcParams(hand="rhand", centre_x_m=float(hinge_f[0]),
                                                      centre_y_m=float(hinge_f[1]), angle_deg=p.open_deg,
                                                      speed_deg_s=p.speed_deg_s, tolerance_m=ARC_TOLERANCE_M))))
        self.set_phase("hold")
        if p.hold_s > 0.0:
            yield Wait(p.hold_s)
        return f"door opened {p.open_deg:.0f} deg about the hinge at ({hinge_f[0]:.3f}, {hinge_f[1]:.3f}) m (F)"
