"""SoftErrorLimiter layer: joint position limits, velocity limits and tracking-error limits on the command."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.core.layer import Layer, Params, Status, described
from controller.core.types import Reference, TickContext
from robot.names import JOINT_GROUPS, JOINT_NAMES

#: the joints an emergency step drives at its own velocity limit
_LEG_JOINTS = np.array(JOINT_GROUPS["rleg"] + JOINT_GROUPS["lleg"])


@dataclass(frozen=True)
class SoftErrorLimiterParams(Params):
    # HRP-2's published numbers give no joint speed limits; 3.5 rad/s bounds what its servos can follow.
    velocity_limit_rad_s: float = field(default=3.5, metadata={"unit": "rad/s", "min": 0.01, "max": 20.0})
    # the legs' limit while the AutoBalancer takes a capture-point emergency step (its `emergency_step` port): the
    # swing must land before the capture point runs past the leg's reach; at 3.5 rad/s the 2x forward push's step
    # lands 0.38 m out with the capture point 0.52 m ahead and the robot falls, at 4.5 it lands 0.44 m out and
    # stands (docs/measurements/walking-and-balance.md, issue 13.3). An assumption as the 3.5 is: what the drives
    # follow for a fraction of a second
    emergency_step_velocity_limit_rad_s: float = field(default=4.5, metadata={"unit": "rad/s", "min": 0.01,
                                                                              "max": 20.0})
    # |command - encoder| larger than this is a servo fault risk (hrpsys error limit)
    error_limit_rad: float = field(default=0.2, metadata={"unit": "rad", "min": 0.001, "max": 3.2})
    position_margin_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 0.2})


def limit_command(q_in: np.ndarray, q_prev: np.ndarray, q_meas: np.ndarray, lower: np.ndarray,
                  upper: np.ndarray, max_step: float, max_error: float) -> np.ndarray:
    """Clamp a joint command: position range, then per-tick step, then distance to the encoder."""
    # np.clip(a, lo, hi) is minimum(maximum(a, lo), hi); the ufuncs directly skip clip's Python overhead
    minimum, maximum = np.minimum, np.maximum
    q = minimum(maximum(q_in, lower), upper)
    q = q_prev + minimum(maximum(q - q_prev, -max_step), max_step)
    q = minimum(maximum(q, q_meas - max_error), q_meas + max_error)
    return minimum(maximum(q, lower), upper)


@dataclass(frozen=True, slots=True)
class LimitedJoints:
    """The joints whose command the SoftErrorLimiter changed this tick, by reason."""

    position: tuple[str, ...] = field(metadata=described("commanded outside the joint range (less the margin)"))
    velocity: tuple[str, ...] = field(metadata=described("commanded faster than the velocity limit"))
    error: tuple[str, ...] = field(metadata=described("commanded too far from the encoder"))


_NOTHING_LIMITED = LimitedJoints((), (), ())


@dataclass(frozen=True, slots=True)
class SoftErrorLimiterStatus(Status):
    limited: LimitedJoints = field(metadata=described("joints limited this tick, by reason"))
    limited_ticks: int = field(metadata=described("ticks with a limited command since the start"))


class SoftErrorLimiter(Layer):
    """Last layer before the servos: nothing outside the joint range, too fast, or too far from the
    encoders reaches the hardware. Reports which joints it limited."""

    name = "el"
    description = "SoftErrorLimiter: joint position, velocity and tracking-error limits"

    def __init__(self, lower_rad: np.ndarray, upper_rad: np.ndarray, q0_rad: np.ndarray,
                 params: SoftErrorLimiterParams | None = None) -> None:
        super().__init__()
        self.params = params or SoftErrorLimiterParams()
        self.lower = np.asarray(lower_rad, dtype=float)
        self.upper = np.asarray(upper_rad, dtype=float)
        self.q_prev = np.array(q0_rad, dtype=float)
        self.limited = _NOTHING_LIMITED
        self.limited_ticks = 0
        self.limited_now = False
        self._range_cache: tuple | None = None  # ((params, lower, upper), lo, hi) of _range

    def set_params(self, params: SoftErrorLimiterParams) -> None:
        self.params = params

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        q_in = ref.q_rad
        if not self.enabled:
            self.q_prev = np.array(q_in, dtype=float)
            return ref
        p = self.params
        lo, hi = self._range(p)
        q_meas = ctx.sensors.q_rad
        max_step = p.velocity_limit_rad_s * ctx.dt_s
        if ctx.ports.emergency_step:  # the AutoBalancer steps this tick: the legs at their emergency limit
            max_step = np.full(len(q_in), max_step)
            max_step[_LEG_JOINTS] = p.emergency_step_velocity_limit_rad_s * ctx.dt_s
        q_prev = self.q_prev
        q = limit_command(q_in, q_prev, q_meas, lo, hi, max_step, p.error_limit_rad)
        self.q_prev = q
        if q.shape == q_in.shape and (q == q_in).all():  # np.array_equal
            if self.limited_now:
                self.limited = _NOTHING_LIMITED
                self.limited_now = False
            return ref
        names = np.array(JOINT_NAMES)
        self.limited = LimitedJoints(
            position=tuple(names[(q_in < lo) | (q_in > hi)].tolist()),
            velocity=tuple(names[np.abs(np.clip(q_in, lo, hi) - q_prev) > max_step + 1e-12].tolist()),
            error=tuple(names[np.abs(q - q_meas) >= p.error_limit_rad - 1e-12].tolist()),
        )
        self.limited_now = True
        self.limited_ticks += 1
        return ref.with_(q_rad=q)

    def _range(self, p: SoftErrorLimiterParams) -> tuple[np.ndarray, np.ndarray]:
        """The joint range less the margin, kept until the parameters or the limits change (2 arrays a tick less)."""
        key = (p, self.lower, self.upper)
        cached = self._range_cache
        if cached is None or any(a is not b for a, b in zip(cached[0], key, strict=True)):
            cached = self._range_cache = (key, self.lower + p.position_margin_rad, self.upper - p.position_margin_rad)
        return cached[1], cached[2]

    def status(self) -> SoftErrorLimiterStatus:
        return SoftErrorLimiterStatus(enabled=self.enabled, limited=self.limited, limited_ticks=self.limited_ticks)
