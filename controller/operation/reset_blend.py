"""After reset_targets(): the operation layer's output blended back onto the upstream reference."""

from __future__ import annotations

import numpy as np

from controller.core.types import Reference
from controller.interpolation.blend import Transition


def _packed(ref: Reference) -> np.ndarray:
    """(joints [rad], BODY position [m], BODY rpy [rad]) of `ref` in one vector."""
    return np.concatenate((ref.q_rad, ref.base_pos_world, ref.base_rpy_rad))


#: a reset's blend is at least this slow on average (the min-jerk peak is 15/8 of it): BODY's roll and pitch
#: [rad/s], its height [m/s] and each joint [rad/s] (soak seed 10110: a 12 deg waist tilt and an operated foot's
#: weight shift undone in the 1 s default raised the capture-point flag)
RESET_TILT_RATE_RAD_S = 0.1
RESET_HEIGHT_SPEED_M_S = 0.05
RESET_JOINT_RATE_RAD_S = 0.5


def reset_duration_s(last_out: Reference, ref: Reference, least_s: float) -> float:
    """[s] the blend from the last output to the upstream reference: least_s, or longer where the rates above
    ask for it."""
    tilt = max(abs(float(a) - float(b)) for a, b in zip(last_out.base_rpy_rad[:2], ref.base_rpy_rad[:2], strict=True))
    height = abs(float(last_out.base_pos_world[2]) - float(ref.base_pos_world[2]))
    joints = float(np.max(np.abs(np.asarray(last_out.q_rad) - np.asarray(ref.q_rad))))
    return max(least_s, tilt / RESET_TILT_RATE_RAD_S, height / RESET_HEIGHT_SPEED_M_S, joints / RESET_JOINT_RATE_RAD_S)


class ResetBlend:
    """From the last output (joints, BODY position and rpy) to the upstream reference by a min-jerk weight over
    `duration_s`; `pending` while it runs."""

    __slots__ = ("_weight", "_start", "pending")

    def __init__(self) -> None:
        self._weight: Transition | None = None
        self._start: np.ndarray | None = None
        self.pending = False  # (an attribute, not a property: read on every idle tick)

    def start(self, last_out: Reference, duration_s: float) -> None:
        self._weight, self._start = Transition(0.0, 1.0, duration_s, "min_jerk"), _packed(last_out)
        self.pending = True

    def cancel(self) -> None:
        """The blend is over (the output is the reference from now on)."""
        self._weight = self._start = None
        self.pending = False

    def step(self, ref: Reference, dt_s: float) -> Reference:
        """The blended output this tick (`ref` itself, and no longer pending, once the weight reaches 1)."""
        w = self._weight.step(dt_s)
        if self._weight.done:
            self.cancel()
            return ref
        x0 = self._start
        x = x0 + w * (_packed(ref) - x0)
        n = len(ref.q_rad)
        return ref.with_owned(q_rad=x[:n], base_pos_world=x[n:n + 3], base_rpy_rad=x[n + 3:n + 6])
