"""`stand`: back to half-sitting: feet apart or turned (after an emergency step, a walk cut short) first step back
side by side (goPos(0, 0, 0): the aligning steps; a stance too wide to walk from is closed by one step first),
then the operation layer's targets back onto the reference and the joints (all but the grippers) interpolated to
HRP-2's half-sitting posture by the SequencePlayer."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output
from controller.core.errors import InvalidState
from controller.walking.auto_balancer_params import WALK_STANCE_MAX_WIDTH_M
from robot.generate import half_sitting_deg
from robot.names import JOINT_NAMES

#: the posture stand goes to, by joint [rad]; the grippers keep what they hold
HALF_SITTING_RAD = {n: math.radians(v) for n, v in zip(JOINT_NAMES, half_sitting_deg(), strict=True)
                    if not n.endswith("ARM_JOINT6")}
#: the left sole in the right sole's frame at half-sitting (x, y [m], yaw [rad]), and how far from it the feet may be
#: and still count as side by side (the leg joints then within ~1 deg of half-sitting)
HALF_SITTING_STANCE = (0.0, 0.19, 0.0)
STANCE_TOLERANCE_M = 0.01
STANCE_TOLERANCE_RAD = math.radians(2.0)
ALIGN_START_TIMEOUT_S = 0.5  # [s] the aligning walk shows in the view a tick after goPos
#: aligning walks before stand gives up: a walk from far apart can end a few cm off (soak seed 10050)
ALIGN_WALKS_MAX = 3
#: [rad] the aligning walk waits for BODY (as the AutoBalancer carries it) this level, [s] at most this long: the
#: reset's blend and, after a motion stop's release, the EmergencyStopper's recovery bring a tilted waist back (soak
#: seed 10167: goPos refused 0.8 s into a 2.8 s return, "straighten the waist first")
LEVEL_RAD = math.radians(2.0)
LEVEL_WAIT_MAX_S = 5.0
#: [s] an operated foot put down and the weight shared again: at most 0.29 m at 0.12 m/s, 0.4 s settled, 1.2 s of
#: shift (controller/walking/foot_lift.py), and a margin
FOOT_DOWN_MAX_S = 5.0

def across_m(lsole_from_rsole) -> float:
    """How far apart the soles' centres are across [m], in the frame of their mean heading."""
    x, y, yaw = lsole_from_rsole
    return abs(-math.sin(0.5 * yaw) * x + math.cos(0.5 * yaw) * y)


def body_tilt_rad(view) -> float:
    """BODY's tilt from the feet frame's vertical [rad], as the AutoBalancer carries it."""
    return math.acos(max(-1.0, min(1.0, float(view.points["waist"].R_feet_point[2][2]))))


def feet_side_by_side(lsole_from_rsole) -> bool:
    x, y, yaw = lsole_from_rsole
    x0, y0, yaw0 = HALF_SITTING_STANCE
    return math.hypot(x - x0, y - y0) <= STANCE_TOLERANCE_M and abs(yaw - yaw0) <= STANCE_TOLERANCE_RAD


@dataclass(frozen=True)
class StandParams(BehaviorParams):
    time_s: float = field(default=2.0, metadata={"unit": "s", "min": 0.5, "max": 10.0,
                                                 "doc": "interpolation time to half-sitting"})


class Stand(Behavior):
    name = "stand"
    Params = StandParams
    _walk_s = 0.0  # [s] the operation targets' reset and the aligning steps' planned durations
    _posture_from_s: float | None = None  # [s] run time the posture's interpolation started (None: not yet)
    _walk_at_s: float | None = None  # [s] run time the aligning walk is asked (None: asked, or none needed)
    _asked_s = 0.0  # [s] run time the last walk was asked
    _closing = False  # the walk under way closes a stance too wide to walk from
    _walks = 0  # the aligning walks asked
    _levelling = False  # the aligning walk waited for BODY to come level
    _reset_s = 0.0  # [s] the operation targets' reset blend before the posture
    summary = "Back to half-sitting (feet side by side first, operation targets reset, joints interpolated)"

    def points(self) -> tuple[str, ...]:
        return ("rhand", "lhand", "head", "waist", "walk")

    def nominal_duration_s(self) -> float:
        return (max(self.params.time_s, self._reset_s) + 0.5 + self._walk_s
                + (LEVEL_WAIT_MAX_S if self._levelling else 0.0))

    def start(self, ctx: Context) -> None:
        view = ctx.require_view()
        if view.walking:
            raise InvalidState("stand refused: the robot is walking; stop it first")
        self._walk_s, self._posture_from_s, self._walked, self._closing, self._walks = 0.0, None, False, False, 0
        if feet_side_by_side(view.lsole_from_rsole):
            self._to_half_sitting(ctx)
            return
        # the operated targets back first: a tilted waist leaves the legs no range to walk (campaign seed 6017); an
        # operated foot goes down with them, and the aligning walk waits for it (campaign seed 1019 with the feet)
        self._walk_s = ctx.commands.reset_operation_targets() + (FOOT_DOWN_MAX_S if view.foot_lifted else 0.0)
        self._walk_at_s = ctx.elapsed_s + self._walk_s - (FOOT_DOWN_MAX_S if view.foot_lifted else 0.0)

    def _walk(self, ctx: Context, lsole_from_rsole) -> None:
        self._walk_at_s, self._walked, self._asked_s = None, False, ctx.elapsed_s
        self._walks += 1
        self._closing = across_m(lsole_from_rsole) > WALK_STANCE_MAX_WIDTH_M  # too wide to walk from: one step first
        self._walk_s += ctx.commands.close_stance() if self._closing else ctx.commands.go_pos(0.0, 0.0, 0.0)

    def _to_half_sitting(self, ctx: Context) -> None:
        self._reset_s = ctx.commands.reset_operation_targets()  # (longer than time_s for a large offset)
        ctx.commands.set_joint_angles(HALF_SITTING_RAD, self.params.time_s)
        self._posture_from_s = ctx.elapsed_s

    def step(self, ctx: Context) -> Output:
        if self._walk_at_s is not None:
            if ctx.elapsed_s >= self._walk_at_s:
                view = ctx.require_view()
                level = body_tilt_rad(view) <= LEVEL_RAD or ctx.elapsed_s - self._walk_at_s > LEVEL_WAIT_MAX_S
                self._levelling = self._levelling or not level
                if view.foot_lifted is None and level:
                    self._walk(ctx, view.lsole_from_rsole)
                elif ctx.elapsed_s - self._walk_at_s > FOOT_DOWN_MAX_S:
                    return self.fail(f"timeout: the {view.foot_lifted} was not down within {FOOT_DOWN_MAX_S:g} s")
            return NOTHING
        if self._posture_from_s is None:
            view = ctx.require_view()
            self._walked = self._walked or view.walking
            if not self._walked and ctx.elapsed_s - self._asked_s > ALIGN_START_TIMEOUT_S:
                return self.fail(f"timeout: the aligning steps did not start within {ALIGN_START_TIMEOUT_S:g} s")
            if view.walking or not self._walked:  # the view is the last tick's: the walk shows from the next one
                return NOTHING
            if self._closing and not feet_side_by_side(view.lsole_from_rsole):  # closed: then the aligning steps
                self._walk(ctx, view.lsole_from_rsole)
                return NOTHING
            if not feet_side_by_side(view.lsole_from_rsole):
                if self._walks < ALIGN_WALKS_MAX:
                    self._walk(ctx, view.lsole_from_rsole)
                    return NOTHING
                x, y, yaw = view.lsole_from_rsole
                return self.fail(f"timeout: {self._walks} aligning walks ended with the feet not side by side (left "
                                 f"sole {x:.3f}, {y:.3f} m, {math.degrees(yaw):.1f} deg from the right one)")
            self._to_half_sitting(ctx)
            return NOTHING
        if ctx.elapsed_s - self._posture_from_s >= max(self.params.time_s, self._reset_s) \
                and not ctx.commands.is_interpolating():
            view = ctx.view
            return self.succeed("standing in half-sitting",
                                waist_height_m=None if view is None else round(view.waist_height_m, 4))
        return NOTHING
