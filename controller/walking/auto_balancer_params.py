"""The AutoBalancer's parameters and status (the gait generator's and the emergency step's among them), the feet's
contact threshold, and the checks of what a walk may start from: the walking point's command and the stance width."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.layer import Params, Status, described
from controller.core.types import WalkCommand
from controller.operation.ranges import (
    WALK_FOOT_DISTANCE_RANGE_M,
    WALK_MAX_ANGULAR_RAD_S,
    WALK_MAX_LINEAR_M_S,
    WALK_MAX_STRIDE_RANGE_M,
)
from controller.walking.emergency_step import EmergencyStepParams
from controller.walking.footsteps import FootstepParams, StrideLimits
from controller.walking.gait_generator import GaitParams
from robot.names import FORCE_SENSOR_NAMES

FEET = (FORCE_SENSOR_NAMES.index("rfsensor"), FORCE_SENSOR_NAMES.index("lfsensor"))
#: [N] a swing foot reading more has touched down (the Stabilizer's contact threshold)
SWING_FOOT_LOADED_N = 25.0

#: [m] the widest stance (the soles' centres across, in their mean heading) a walk starts from: measured from 0.32 m
#: with the swing knee 7 deg from straight, from 0.36 m it straightens and raises the flag (a wide catching step)
WALK_STANCE_MAX_WIDTH_M = 0.34


def stance_width_m(T_world_rfoot: np.ndarray, T_world_lfoot: np.ndarray) -> float:
    """How far apart the soles' centres are across [m]: in the frame of their mean heading."""
    yaw = math.atan2(T_world_rfoot[1, 0] + T_world_lfoot[1, 0], T_world_rfoot[0, 0] + T_world_lfoot[0, 0])
    dx, dy = (T_world_lfoot[:2, 3] - T_world_rfoot[:2, 3]).tolist()
    return abs(-math.sin(yaw) * dx + math.cos(yaw) * dy)


def check_walk_command(cmd: WalkCommand) -> None:
    """Raise InvalidCommand naming the field and the allowed range when the walking point's command is not
    one the AutoBalancer takes (what the operation layer and the verbs check before it reaches the loop)."""
    for name, value, limit, unit in (("vx_m_s", cmd.vx_m_s, WALK_MAX_LINEAR_M_S, "m/s"),
                                     ("vy_m_s", cmd.vy_m_s, WALK_MAX_LINEAR_M_S, "m/s"),
                                     ("vtheta_rad_s", cmd.vtheta_rad_s, WALK_MAX_ANGULAR_RAD_S, "rad/s")):
        if not (math.isfinite(value) and abs(value) <= limit):
            raise InvalidCommand(f"walk.{name}={value!r} [{unit}]; allowed: [{-limit:g}, {limit:g}]")
    for name, value, (lo, hi) in (("max_stride_m", cmd.max_stride_m, WALK_MAX_STRIDE_RANGE_M),
                                  ("foot_distance_m", cmd.foot_distance_m, WALK_FOOT_DISTANCE_RANGE_M)):
        if value is not None and not (math.isfinite(value) and lo <= value <= hi):
            raise InvalidCommand(f"walk.{name}={value!r} [m]; allowed: [{lo:g}, {hi:g}] or null (the gait's own)")


def walk_command_valid(cmd: WalkCommand) -> bool:
    """check_walk_command as a yes or no."""
    try:
        check_walk_command(cmd)
    except InvalidCommand:
        return False
    return True


@dataclass(frozen=True)
class AutoBalancerParams(Params):
    """The AutoBalancer's parameters, the gait generator's among them (hrpsys setGaitGeneratorParam): a change
    applies to the footsteps planned from then on (a velocity walk's at its next mid-step check)."""

    transition_time_s: float = field(default=2.0, metadata={"unit": "s", "min": 0.01, "max": 10.0})
    use_hand_force_offset: bool = field(default=True, metadata={"unit": "-"})
    # preview-control weights (ZMP error, jerk); a change applies at the next standstill (PREVIEW_GAINS_DELAY_S)
    preview_q: float = field(default=1.0, metadata={"unit": "-", "min": 1e-6, "max": 1e6,
                                                    "doc": "preview control's ZMP-error weight"})
    preview_r: float = field(default=1e-6, metadata={"unit": "-", "min": 1e-12, "max": 1.0,
                                                     "doc": "preview control's jerk weight"})
    # gait (hrpsys default_step_time, rounded to whole control ticks; default_step_height; toe/heel angles)
    step_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.4, "max": 5.0})
    step_height_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.2})
    toe_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 0.6})
    heel_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 0.6})
    # share of each step's time in double support at its start and at its end (hrpsys default_double_support_ratio_*)
    double_support_ratio_before: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    double_support_ratio_after: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    # largest feet mid-coords displacement per step (hrpsys stride_parameter); "inside": towards the support foot
    stride_fwd_x_m: float = field(default=0.15, metadata={"unit": "m", "min": 0.0, "max": 0.4})
    stride_bwd_x_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.3})
    stride_outside_y_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.3})
    stride_inside_y_m: float = field(default=0.025, metadata={"unit": "m", "min": 0.0, "max": 0.3})
    stride_outside_th_rad: float = field(default=math.radians(10.0), metadata={"unit": "rad", "min": 0.0, "max": 0.8})
    stride_inside_th_rad: float = field(default=math.radians(5.0), metadata={"unit": "rad", "min": 0.0, "max": 0.8})
    # distance between the feet's centres when walking (hrpsys leg_default_translate_pos, both legs)
    foot_distance_m: float = field(default=0.19, metadata={"unit": "m", "min": WALK_FOOT_DISTANCE_RANGE_M[0],
                                                           "max": WALK_FOOT_DISTANCE_RANGE_M[1]})
    # the Stabilizer's capture-point flag rising while walking (Ports.cp_flag, its estop_while_walking) calls the
    # emergency walking stop: the steps end in place while the EmergencyStopper holds the motion
    walking_stop_on_cp_flag: bool = field(default=True, metadata={"unit": "-"})
    # ... by a capture step (issue 26): the walk ends where it is, a foot in the air lands where the capture point
    # will be (the emergency step below, from the swing in progress), both feet down stand; false: hrpsys'
    # emergencyStop, steps in place after the committed ones
    walking_capture_step: bool = field(default=True, metadata={"unit": "-"})
    # the capture-point emergency step (issue 13.3; controller/walking/emergency_step.py): its switch, when it
    # steps and how, each field's unit and range declared once on EmergencyStepParams
    emergency_step: EmergencyStepParams = field(default=EmergencyStepParams(), metadata={
        "doc": "the capture-point emergency step (EmergencyStepParams)"})

    #: the flat names of before the nested emergency_step (sessions and parameter documents recorded then) -> now
    RENAMED: ClassVar[dict[str, str]] = {
        "emergency_step_" + old: "emergency_step." + new for old, new in (
            ("cp_margin_m", "cp_margin_m"), ("zmp_margin_m", "zmp_margin_m"),
            ("initial_double_support_s", "initial_double_support_s"), ("time_s", "step_time_s"),
            ("double_support_ratio", "double_support_ratio"), ("final_double_support_s", "final_double_support_s"),
            ("height_m", "step_height_m"), ("max_forward_m", "max_forward_m"), ("max_backward_m", "max_backward_m"),
            ("min_width_m", "min_width_m"), ("max_width_m", "max_width_m"), ("landing_offset_m", "landing_offset_m"),
            ("replan_until_s", "replan_until_s"), ("zmp_shift_s", "zmp_shift_s"),
            ("base_lowering_m", "base_lowering_m"))}

    #: nested fields that also take a boolean, their switch alone (the flat switch of before: `emergency_step: false`)
    SWITCHES: ClassVar[dict[str, str]] = {"emergency_step": "enabled"}

    @classmethod
    def current_names(cls, changes):
        """`changes` with the old flat names as the nested fields they became; the old switch `emergency_step`
        (a boolean, where now the nested parameters are) is `emergency_step.enabled`."""
        out = {}
        for name, value in changes.items():
            if name in cls.SWITCHES and isinstance(value, bool):
                name = f"{name}.{cls.SWITCHES[name]}"
            out[cls.RENAMED.get(name, name)] = value
        return out

    def gait_params(self, base: GaitParams | None = None) -> GaitParams:
        return (base or GaitParams()).replaced(double_support_ratio_before=self.double_support_ratio_before,
                                               double_support_ratio_after=self.double_support_ratio_after)

    def footstep_params(self, dt_s: float, base: FootstepParams | None = None) -> FootstepParams:
        step_time = max(1, round(self.step_time_s / dt_s)) * dt_s  # a whole number of control ticks
        return (base or FootstepParams()).replaced(step_time_s=step_time, step_height_m=self.step_height_m,
                                                   toe_angle_rad=self.toe_angle_rad,
                                                   heel_angle_rad=self.heel_angle_rad,
                                                   leg_offset_y_m=0.5 * self.foot_distance_m)

    def stride_limits(self) -> StrideLimits:
        return StrideLimits(fwd_x_m=self.stride_fwd_x_m, outside_y_m=self.stride_outside_y_m,
                            outside_th_rad=self.stride_outside_th_rad, bwd_x_m=self.stride_bwd_x_m,
                            inside_y_m=self.stride_inside_y_m, inside_th_rad=self.stride_inside_th_rad)


@dataclass(frozen=True, slots=True)
class FootstepStatus:
    """A planned footstep not landed yet, world frame."""

    leg: str = field(metadata=described("'rleg' or 'lleg'"))
    pos: tuple[float, float, float] = field(metadata=described("sole position", "m"))
    rpy: tuple[float, float, float] = field(metadata=described("sole roll, pitch, yaw", "rad"))
    step_time_s: float = field(metadata=described("duration of the step", "s"))
    step_height_m: float = field(metadata=described("swing height", "m"))


@dataclass(frozen=True, slots=True)
class EmergencyStepRecord:
    """A capture-point emergency step the AutoBalancer took, world frame."""

    leg: str = field(metadata=described("the leg that stepped, 'rleg' or 'lleg'"))
    time_s: float = field(metadata=described("simulated time the step was triggered", "s"))
    cp_at_trigger: tuple[float, float] = field(metadata=described("measured capture point at the trigger", "m"))
    landing: tuple[float, float] = field(metadata=described(
        "where the sole lands (x, y): the target while stepping, where it touched down once landed", "m"))
    landed: bool = field(metadata=described("the foot is down"))
    landed_early: bool = field(metadata=described("it touched down before the planned time (where it was)"))


@dataclass(frozen=True, slots=True)
class AutoBalancerStatus(Status):
    active: bool = field(metadata=described("the AutoBalancer is running (started)"))
    weight: float = field(metadata=described("start/stop blend weight, 0..1", "-"))
    walking: bool = field(metadata=described("a walk is in progress"))
    support: str = field(metadata=described("support phase: 'both', 'rleg' or 'lleg'"))
    walking_stop: bool = field(metadata=described("the emergency walking stop is in force (stepping in place)"))
    has_ik_failed: bool = field(metadata=described("the whole-body IK could not reach its targets this tick"))
    footsteps: tuple[FootstepStatus, ...] = field(metadata=described("the footsteps not landed yet"))
    walk_point: str = field(default="idle", metadata=described(
        "the walking point (Ports.walk_command): 'idle', 'walking' (abc walks at it), or 'ignored: <why>'"))
    preview_gains: str = field(default="current", metadata=described(
        "'current', or 'pending': new preview_q / preview_r wait for the next standstill"))
    emergency_step: bool = field(default=False, metadata=described(
        "a capture-point emergency step is in progress: goPos, goVelocity, setFootSteps and the walking point are "
        "refused and the EmergencyStopper holds the motion"))
    emergency_steps: tuple[EmergencyStepRecord, ...] = field(default=(), metadata=described(
        "the emergency steps taken, oldest first (the last 10)"))
    walk_cut: str | None = field(default=None, metadata=described(
        "why the last walk ended before its plan, and when (the capture-point flag, or a capture-point error with "
        "both feet down); None when it ended as planned or a new walk began"))
    walk_height_lowering_m: float = field(default=0.0, metadata=described(
        "how far BODY is held below the operated waist height because a walk is on: walking plans at the "
        "half-sitting height (a raised waist stretches the swing leg straight when the COM shifts over the "
        "stance foot)", "m"))
    foot_lift: str = field(default="idle", metadata=described(
        "a foot operational point's phase: 'idle', 'shifting' (the COM to the stance foot), 'lifted', 'lowering', "
        "'returning' (the weight shared again), or 'ignored: <why>' for a lift refused this tick"))
    lifted_foot: str | None = field(default=None, metadata=described("the foot being lifted ('rfoot', 'lfoot')"))

