"""`release`: open a hand's gripper fully."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output
from behaviors.gripper import SETTLED_RAD_S, JawRate, gripper_joint

OPEN_TOLERANCE_RAD = math.radians(2.0)
OPEN_LAG_S = 0.1  # [s] the jaw is checked no sooner than this after its command has arrived (the servo's lag)


@dataclass(frozen=True)
class ReleaseParams(BehaviorParams):
    hand: str = field(default="rhand", metadata={"unit": "-", "choices": ("rhand", "lhand"), "doc": "which hand"})
    time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.2, "max": 5.0,
                                                 "doc": "opening time, closed to open"})


class Release(Behavior):
    name = "release"
    Params = ReleaseParams
    summary = "Open a gripper fully"

    def resources(self) -> tuple[str, ...]:
        return (f"{self.params.hand}.gripper",)

    def nominal_duration_s(self) -> float:
        return self.params.time_s + OPEN_LAG_S + 1.0

    def start(self, ctx: Context) -> None:
        self.joint = gripper_joint(self.params.hand)
        r = ctx.commands.joint(self.joint)
        self.open_rad = r.lower_rad
        # timed for the whole span, closed to open: the joint reading gives the limited command, not the
        # reference the opening starts from, and a grasp at the hand's limit leaves that reference shut (the
        # servo's torque cap holds the force). Timed from the jaw, the reference was still coming down to it
        # when the jaw was checked: "33 deg short of open", the jaw not moving yet (seed 1, two trials).
        self.open_s = max(ctx.dt_s, self.params.time_s)
        self.rate = JawRate(ctx.dt_s)
        self.rate.update(r.q_meas_rad)
        ctx.commands.set_joint_angles({self.joint: self.open_rad}, self.open_s)

    def step(self, ctx: Context) -> Output:
        r = ctx.commands.joint(self.joint)
        dq = self.rate.update(r.q_meas_rad)
        if ctx.elapsed_s < self.open_s + OPEN_LAG_S or abs(dq) > SETTLED_RAD_S:
            return NOTHING
        gap = r.q_meas_rad - self.open_rad
        if gap <= OPEN_TOLERANCE_RAD:
            return self.succeed("gripper open", jaw_deg=round(math.degrees(r.q_meas_rad), 3))
        return self.fail(f"the jaw stopped {math.degrees(gap):.1f} deg short of open",
                         jaw_deg=round(math.degrees(r.q_meas_rad), 3))

    def stop(self, ctx: Context) -> None:
        r = ctx.commands.joint(self.joint)
        here = min(max(r.q_meas_rad, r.lower_rad), r.upper_rad)
        ctx.commands.set_joint_angles({self.joint: here}, ctx.dt_s)
