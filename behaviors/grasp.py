"""`grasp`: close a hand's gripper; if an object stops the jaw, squeeze it with a set fingertip force
(at most the JRL-hand's 14 N), sensed from the servo's error; a jaw that closes on nothing is reported."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output
from behaviors.gripper import (
    FINGERTIP_LIMIT_N,
    SETTLED_RAD_S,
    JawRate,
    fingertip_force_n,
    gripper_joint,
    squeeze_offset_rad,
)

EMPTY_GAP_RAD = math.radians(2.0)  # the jaw within this of its closing limit holds nothing
SQUEEZE_TIME_S = 0.1  # [s] to move the command to the squeezing angle
HOLD_CHECK_S = 0.3  # [s] the squeeze is held this long before the force is read


@dataclass(frozen=True)
class GraspParams(BehaviorParams):
    hand: str = field(default="rhand", metadata={"unit": "-", "choices": ("rhand", "lhand"), "doc": "which hand"})
    force_n: float = field(default=10.0, metadata={"unit": "N", "min": 1.0, "max": FINGERTIP_LIMIT_N,
                                                   "doc": "fingertip force to hold with (JRL-hand: 14 N at most)"})
    time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.2, "max": 5.0,
                                                 "doc": "closing time, open to closed"})
    require_object: bool = field(default=True, metadata={"unit": "-", "doc": "fail when the jaw closes on "
                                                         "nothing (false: a full close succeeds)"})


class Grasp(Behavior):
    name = "grasp"
    Params = GraspParams
    summary = "Close a gripper and hold what it meets with force_n (14 N fingertip limit)"

    def resources(self) -> tuple[str, ...]:
        return (f"{self.params.hand}.gripper",)

    def nominal_duration_s(self) -> float:
        return self.params.time_s + SQUEEZE_TIME_S + HOLD_CHECK_S + 1.0

    def start(self, ctx: Context) -> None:
        self.joint = gripper_joint(self.params.hand)
        r = ctx.commands.joint(self.joint)
        self.closed_rad = r.upper_rad
        span = r.upper_rad - r.lower_rad
        # the closing time scales with the part of the span left to close
        self.close_s = max(ctx.dt_s, self.params.time_s * max(0.0, r.upper_rad - r.q_meas_rad) / span)
        self.rate = JawRate(ctx.dt_s)
        self.rate.update(r.q_meas_rad)
        self.phase = "closing"
        self.phase_s = 0.0
        ctx.commands.set_joint_angles({self.joint: self.closed_rad}, self.close_s)

    def step(self, ctx: Context) -> Output:
        r = ctx.commands.joint(self.joint)
        dq = self.rate.update(r.q_meas_rad)
        force = fingertip_force_n(r.q_cmd_rad, r.q_meas_rad, dq)
        self.result["force_n"] = round(force, 3)
        self.result["jaw_deg"] = round(math.degrees(r.q_meas_rad), 3)
        if self.phase == "closing":
            if ctx.elapsed_s < self.close_s or abs(dq) > SETTLED_RAD_S:
                return NOTHING
            if self.closed_rad - r.q_meas_rad <= EMPTY_GAP_RAD:
                if self.params.require_object:
                    return self.fail("the jaw closed on nothing", holding=False)
                return self.succeed("gripper closed (nothing between the jaws)", holding=False)
            if self.params.force_n >= FINGERTIP_LIMIT_N:
                # at the hand's limit the servo's torque cap holds the force: commanded shut, it keeps pressing
                # 14 N as the pads creep into the can (commanded 14 N past the jaw instead, the jaw crept 1.3 deg
                # shut in 75 s of holding and walking, the force fell to 1.4 N and the can slid out on the way
                # down to the hole)
                target = self.closed_rad
            else:
                target = min(self.closed_rad, r.q_meas_rad + squeeze_offset_rad(self.params.force_n))
            ctx.commands.set_joint_angles({self.joint: target}, SQUEEZE_TIME_S)
            self.phase, self.phase_s = "squeezing", ctx.elapsed_s
            return NOTHING
        if ctx.elapsed_s - self.phase_s < SQUEEZE_TIME_S + HOLD_CHECK_S:
            return NOTHING
        if force < 0.5 * self.params.force_n:
            return self.fail(f"the object slipped: {force:.1f} N at the fingertip", holding=False)
        return self.succeed(f"holding with {force:.1f} N at the fingertip", holding=True)

    def stop(self, ctx: Context) -> None:
        r = ctx.commands.joint(self.joint)  # interrupted: the jaw stops where it is
        here = min(max(r.q_meas_rad, r.lower_rad), r.upper_rad)
        ctx.commands.set_joint_angles({self.joint: here}, ctx.dt_s)
