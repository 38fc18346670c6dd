"""The one start/stop blend of the chain: a weight going smoothly from one value to another over a stated
time (a layer starting or stopping), and the blend from a held output back to the live, moving input
(the stoppers' release) built on it."""

from __future__ import annotations

import math

import numpy as np

from controller.core.errors import InvalidCommand
from controller.interpolation.hoff_arbib import hoff_arbib

#: the profiles a transition can follow, progress s in [0, 1] -> ratio in [0, 1], rest to rest
SHAPES = ("sigmoid", "min_jerk")

_SIGMOID_STEEPNESS = 9.19  # hrpsys Stabilizer / ImpedanceController transition: 1 / (1 + exp(-9.19 (s - 0.5)))


def _raw_sigmoid(x: float) -> float:
    return 1.0 / (1.0 + math.exp(-_SIGMOID_STEEPNESS * (x - 0.5)))


_SIGMOID_LO, _SIGMOID_HI = _raw_sigmoid(0.0), _raw_sigmoid(1.0)


def sigmoid_ratio(s: float) -> float:
    """hrpsys's start/stop curve for progress s in [0, 1], rescaled to be exactly 0 at s = 0 and 1 at s = 1
    (hrpsys's own curve jumps by 1 % at both ends)."""
    return (_raw_sigmoid(min(1.0, max(0.0, s))) - _SIGMOID_LO) / (_SIGMOID_HI - _SIGMOID_LO)


class Transition:
    """A weight from `w0` to `w1` over `duration_s`, following `shape` ("sigmoid": hrpsys's Stabilizer and
    ImpedanceController curve; "min_jerk": the Hoff-Arbib path, the AutoBalancer's). `step(dt)` advances and
    returns the weight; at the end it is exactly `w1` and `done` is true."""

    __slots__ = ("w0", "w1", "duration_s", "shape", "elapsed_s", "weight", "_segment")

    def __init__(self, w0: float, w1: float, duration_s: float, shape: str = "sigmoid") -> None:
        if shape not in SHAPES:
            raise InvalidCommand(f"unknown transition shape {shape!r}; valid: {', '.join(SHAPES)}")
        if not duration_s > 0.0:
            raise InvalidCommand(f"transition duration {duration_s!r} s; must be > 0")
        self.w0, self.w1, self.duration_s, self.shape = float(w0), float(w1), float(duration_s), shape
        self.elapsed_s = 0.0
        self.weight = self.w0
        self._segment = hoff_arbib(np.array([self.w0]), np.array([self.w1]), self.duration_s) \
            if shape == "min_jerk" else None

    def __repr__(self) -> str:
        return (f"Transition({self.w0:g} -> {self.w1:g} over {self.duration_s:g} s, {self.shape}, "
                f"at {self.elapsed_s:.3f} s)")

    @property
    def done(self) -> bool:
        return self.elapsed_s >= self.duration_s

    def step(self, dt_s: float) -> float:
        if self._segment is not None:
            self.elapsed_s = min(self.elapsed_s + dt_s, self.duration_s)
            self.weight = float(self._segment.sample(self.elapsed_s)[0][0])
            return self.weight
        self.elapsed_s += dt_s
        s = min(1.0, self.elapsed_s / self.duration_s)
        self.weight = self.w0 + (self.w1 - self.w0) * sigmoid_ratio(s) if s < 1.0 else self.w1
        return self.weight


class RecoverBlend:
    """From `x0` at rest back to a live, possibly moving input over `duration_s`: output = x0 + w (input - x0)
    with w a min-jerk Transition from 0 to 1 (hrpsys's recover interpolation); exactly the input at the end.

    `carry_motion`: the input's own motion passes unscaled and only the gap found at the first step is blended
    out, output = input + (1 - w) (x0 - input_0) (the same for a still input)."""

    def __init__(self, x0: np.ndarray, duration_s: float, carry_motion: bool = False) -> None:
        self.x0 = np.array(x0, dtype=float)
        self._weight = Transition(0.0, 1.0, max(float(duration_s), 1e-9), "min_jerk")
        self._carry_motion = carry_motion
        self._gap: np.ndarray | None = None  # x0 - the first input, with carry_motion

    @property
    def done(self) -> bool:
        return self._weight.done

    @property
    def remaining_s(self) -> float:
        return max(0.0, self._weight.duration_s - self._weight.elapsed_s)

    def step(self, target: np.ndarray, dt_s: float) -> np.ndarray:
        w = self._weight.step(dt_s)
        target = np.asarray(target, dtype=float)
        if self._weight.done:
            return target.copy()
        if self._carry_motion:
            if self._gap is None:
                self._gap = self.x0 - target
            return target + (1.0 - w) * self._gap
        return self.x0 + w * (target - self.x0)
