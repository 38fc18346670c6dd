"""`stand`: back to half-sitting: the operation layer's targets back onto the reference, the joints (all but
the grippers) interpolated to HRP-2's half-sitting posture by the SequencePlayer."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output
from controller.core.errors import InvalidState
from robot.generate import half_sitting_deg
from robot.names import JOINT_NAMES

#: the posture stand goes to, by joint [rad]; the grippers keep what they hold
HALF_SITTING_RAD = {n: math.radians(v) for n, v in zip(JOINT_NAMES, half_sitting_deg(), strict=True)
                    if not n.endswith("ARM_JOINT6")}


@dataclass(frozen=True)
class StandParams(BehaviorParams):
    time_s: float = field(default=2.0, metadata={"unit": "s", "min": 0.5, "max": 10.0,
                                                 "doc": "interpolation time to half-sitting"})


class Stand(Behavior):
    name = "stand"
    Params = StandParams
    summary = "Back to half-sitting (operation targets reset, joints interpolated)"

    def points(self) -> tuple[str, ...]:
        return ("rhand", "lhand", "head", "waist")

    def nominal_duration_s(self) -> float:
        return self.params.time_s + 0.5

    def start(self, ctx: Context) -> None:
        view = ctx.require_view()
        if view.walking:
            raise InvalidState("stand refused: the robot is walking; stop it first")
        ctx.commands.reset_operation_targets()
        ctx.commands.set_joint_angles(HALF_SITTING_RAD, self.params.time_s)

    def step(self, ctx: Context) -> Output:
        if ctx.elapsed_s >= self.params.time_s and not ctx.commands.is_interpolating():
            view = ctx.view
            return self.succeed("standing in half-sitting",
                                waist_height_m=None if view is None else round(view.waist_height_m, 4))
        return NOTHING
