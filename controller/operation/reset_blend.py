"""After reset_targets(): the operation layer's output blended back onto the upstream reference."""

from __future__ import annotations

import numpy as np

from controller.core.types import Reference
from controller.interpolation.blend import Transition


def _packed(ref: Reference) -> np.ndarray:
    """(joints [rad], BODY position [m], BODY rpy [rad]) of `ref` in one vector."""
    return np.concatenate((ref.q_rad, ref.base_pos_world, ref.base_rpy_rad))


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
