"""The operated points' targets in the feet frame F: integrated from the summed twists, settled on what the IK
achieved, why each point did less than asked, and the anchor the hands are held relative to."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from controller.core.types import read_only
from controller.operation.integration import PointLimits, integrate_point
from controller.operation.limits import HAND_STEP_LENGTH_M, JOINT_LIMIT, MOTION_STOP, REACH, VELOCITY, clamp_to_achieved
from controller.operation.points import ZERO_TWIST, Twist
from controller.operation.targets import HandPose

IK_POINTS = ("rhand", "lhand", "head", "waist")  # the points the IK realises ("walk" goes to the AutoBalancer)
HANDS = ("rhand", "lhand")
_ZERO3 = read_only(np.zeros(3))


class PointTargets:
    """Per operated point: `targets` (HandPose | GazeAngles | WaistPose, in F; the hands relative to `anchor`),
    `achieved` (the IK's pose, same layout), `limited` (why it did less: controller.operation.limits' reasons or
    None) and `rates` (the twist integrated last tick; none: at rest). Standing the hands are held in F
    (`anchor` 0), walking relative to BODY (`anchor` BODY in F); `neck_feet_m` is the gaze ray's origin."""

    __slots__ = ("targets", "achieved", "limited", "rates", "_limits", "anchor", "anchored_walking", "neck_feet_m")

    def __init__(self) -> None:
        self.targets: dict[str, object] = {}
        self.achieved: dict[str, object] = {}
        self.limited: dict[str, str | None] = {}
        self.rates: dict[str, Twist] = {}
        self._limits = PointLimits()  # speed limits and acceleration steps per IK point, from the params
        self.anchor: np.ndarray = _ZERO3  # BODY in F while walking, else 0
        self.anchored_walking = False  # the hand targets are held relative to BODY
        self.neck_feet_m: np.ndarray | None = None

    def clear(self) -> None:
        """Nothing operated: no target, at rest."""
        self.targets.clear()
        self.rates.clear()
        self.achieved.clear()
        self.limited.clear()

    def integrate(self, total: dict[str, Twist], params, dt_s: float,
                  seed: Callable[[str], object]) -> dict[str, HandPose]:
        """One tick of each IK point's summed twist (`total`; a point at rest without one is skipped, one still
        moving slows down to rest) integrated into its target, `seed(point)` giving a point's first target; the
        speed limits and the acceleration steps from `params` (OperationParams). Returns the hands' targets
        before this step."""
        stepped_from: dict[str, HandPose] = {}
        rates, targets, limited, limits = self.rates, self.targets, self.limited, self._limits
        for point in IK_POINTS:
            twist = total.get(point)
            previous = rates.get(point)
            if twist is None or twist.is_zero:
                if previous is None:
                    continue
                twist = ZERO_TWIST  # slowing down to rest
            if point not in targets:
                targets[point] = seed(point)
            step = integrate_point(targets[point], twist, previous, limits.speed(params, point),
                                   limits.accel_steps(params, point, dt_s), dt_s)
            if step.rate is None:
                rates.pop(point, None)
            else:
                rates[point] = step.rate
            if point in HANDS:
                stepped_from[point] = targets[point]
            targets[point] = step.target
            limited[point] = VELOCITY if step.velocity_limited else None
        return stepped_from

    def settle(self, point: str, achieved, reason: str | None, stopped: bool,
               stepped_from: dict[str, HandPose]) -> None:
        """The IK achieved `achieved` for `point` (limited for `reason`, None: it followed): a hand limited by its
        reach or a joint advances by the share of its step made along the asked direction (`stepped_from`: its
        target before the step), else a limited target is clamped to the achieved pose (no wind-up)."""
        self.achieved[point] = achieved
        if stopped:
            self.limited[point] = MOTION_STOP
        elif reason is not None:
            self.limited[point] = reason
            start = stepped_from.get(point)
            if start is not None and reason in (REACH, JOINT_LIMIT):
                # one scale for the whole step, never sideways with the IK's best effort, which drifted the hand
                # off the asked line along the workspace's edge
                self.targets[point] = start.advanced_along(self.targets[point], achieved, HAND_STEP_LENGTH_M)
            else:
                self.targets[point] = clamp_to_achieved(self.targets[point], achieved, reason)
        elif self.limited.get(point) != VELOCITY:
            self.limited[point] = None

    def re_anchor(self, walking: bool, shift: np.ndarray) -> None:
        """Walking started (shift = BODY in F) or stopped (shift = -BODY in F): the hand targets and the neck
        re-expressed relative to the new anchor, the same place in F at this tick."""
        self.anchored_walking = walking
        for store in (self.targets, self.achieved):
            for point in HANDS:
                if point in store:
                    store[point] = HandPose.of(store[point].p_feet_m - shift, store[point].R_feet_hand)
        if self.neck_feet_m is not None:
            self.neck_feet_m = self.neck_feet_m - shift
