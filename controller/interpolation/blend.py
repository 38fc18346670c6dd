"""Blending from a held posture back to a live (moving) input: hrpsys's recover interpolation, a
Hoff-Arbib move re-planned every tick toward the current input over the remaining time."""

from __future__ import annotations

import numpy as np

from controller.interpolation.hoff_arbib import quintic_step


class RecoverBlend:
    """Start at `x0` at rest; `step(target, dt)` moves toward the moving `target`, reaching it exactly
    after `duration_s` with zero relative velocity and acceleration (if the target is at rest)."""

    def __init__(self, x0: np.ndarray, duration_s: float) -> None:
        self.x = np.array(x0, dtype=float)
        self.v = np.zeros_like(self.x)
        self.a = np.zeros_like(self.x)
        self.remaining_s = float(duration_s)

    @property
    def done(self) -> bool:
        return self.remaining_s <= 1e-12

    def step(self, target: np.ndarray, dt_s: float) -> np.ndarray:
        target = np.asarray(target, dtype=float)
        if self.remaining_s <= dt_s + 1e-12:
            self.remaining_s = 0.0
            self.x, self.v, self.a = target.copy(), np.zeros_like(self.x), np.zeros_like(self.x)
            return self.x.copy()
        self.x, self.v, self.a = quintic_step(self.x, self.v, self.a, target, self.remaining_s, dt_s)
        self.remaining_s -= dt_s
        return self.x.copy()
