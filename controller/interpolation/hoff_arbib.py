"""Hoff-Arbib minimum-jerk interpolation (paper Sec. III-A, Eq. 1-2; hrpsys `interpolator` HOFFARBIB):
closed-form quintics from the current (x, v, a) to a goal, and a track that plays a queue of them.

Every function is vectorised over the last axis (one column per interpolated dimension); times are
seconds, the units of x are whatever the caller interpolates ([rad], [m], [N], ...).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

__all__ = [
    "HoffArbibTrack",
    "Segment",
    "eq1_jerk",
    "hoff_arbib",
    "quintic_basis",
    "quintic_coefficients",
    "quintic_jerk",
    "quintic_state",
    "quintic_step",
    "quintic_xva",
    "stopping_goal",
    "via_velocities",
]

#: A segment whose end lies closer than this to the time cursor is finished [s] (float round-off of
#: summed control periods, far below any control period).
END_TOLERANCE_S = 1e-9


def quintic_coefficients(x, v, a, goal_x, duration_s: float, goal_v=0.0, goal_a=0.0) -> np.ndarray:
    """Coefficients (6, n) of the quintic from (x, v, a) to (goal_x, goal_v, goal_a) in `duration_s`.

    As hrpsys `interpolator::setGoal` (HOFFARBIB): with T the remaining time,
    A = (gx - (x + vT + aT^2/2)) / T^3, B = (gv - (v + aT)) / T^2, C = (ga - a) / T and
    c = [x, v, a/2, 10A - 4B + C/2, (-15A + 7B - C)/T, (6A - 3B + C/2)/T^2]; local time runs from 0.
    """
    T = float(duration_s)
    if not T > 0.0:
        raise ValueError(f"duration_s must be > 0, got {duration_s!r}")
    x, v, a, gx, gv, ga = np.broadcast_arrays(
        *(np.asarray(z, dtype=float) for z in (x, v, a, goal_x, goal_v, goal_a)))
    A = (gx - (x + v * T + a * (T * T / 2.0))) / T**3
    B = (gv - (v + a * T)) / T**2
    C = (ga - a) / T
    return np.stack([
        x.copy(),
        v.copy(),
        a / 2.0,
        10.0 * A - 4.0 * B + 0.5 * C,
        (-15.0 * A + 7.0 * B - C) / T,
        (6.0 * A - 3.0 * B + 0.5 * C) / T**2,
    ])


def quintic_basis(t_s: float) -> np.ndarray:
    """(3, 6) rows mapping quintic coefficients to position, velocity and acceleration at `t_s`."""
    t = float(t_s)
    t2 = t * t
    t3 = t2 * t
    return np.array([
        [1.0, t, t2, t3, t3 * t, t3 * t2],
        [0.0, 1.0, 2.0 * t, 3.0 * t2, 4.0 * t3, 5.0 * t3 * t],
        [0.0, 0.0, 2.0, 6.0 * t, 12.0 * t2, 20.0 * t3],
    ])


def quintic_xva(coeffs: np.ndarray, t_s: float) -> np.ndarray:
    """Stacked (3, n) position, velocity and acceleration of the quintic `coeffs` (6, n) at `t_s`."""
    if coeffs.ndim <= 2:
        return quintic_basis(t_s) @ coeffs
    return np.tensordot(quintic_basis(t_s), coeffs, axes=1)


def quintic_state(coeffs: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration of the quintic `coeffs` (6, n) at local time `t_s`."""
    x, v, a = quintic_xva(coeffs, t_s)
    return x, v, a


def quintic_jerk(coeffs: np.ndarray, t_s: float) -> np.ndarray:
    """Jerk (third derivative) of the quintic `coeffs` (6, n) at local time `t_s`."""
    _, _, _, c3, c4, c5 = coeffs
    t = float(t_s)
    return 6.0 * c3 + t * (24.0 * c4 + t * (60.0 * c5))


def eq1_jerk(x, v, a, x_cmd, t_ha_s: float) -> np.ndarray:
    """Paper Eq. 1: jerk = -9 a / t_ha - 36 v / t_ha^2 + 60 (x_cmd - x) / t_ha^3, t_ha the remaining time."""
    t = float(t_ha_s)
    x, v, a, x_cmd = (np.asarray(z, dtype=float) for z in (x, v, a, x_cmd))
    return -9.0 * a / t - 36.0 * v / t**2 + 60.0 * (x_cmd - x) / t**3


def min_jerk(s):
    """Rest-to-rest minimum-jerk ratio 10 s^3 - 15 s^4 + 6 s^5 for progress s in [0, 1] (clipped): the
    Hoff-Arbib path from 0 to 1 (Eq. 1-2 with zero end velocities and accelerations)."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def quintic_step(x, v, a, goal_x, remaining_s: float,
                 dt_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One control period of a Hoff-Arbib move re-planned from (x, v, a) toward `goal_x` (rest at the goal).

    Returns the state after `dt_s`; if `dt_s` reaches the end of `remaining_s`, exactly the goal at rest.
    """
    goal_x = np.asarray(goal_x, dtype=float)
    if dt_s >= remaining_s - END_TOLERANCE_S:
        zeros = np.zeros(np.broadcast_shapes(np.shape(x), goal_x.shape))
        return np.broadcast_to(goal_x, zeros.shape).copy(), zeros, zeros.copy()
    return quintic_state(quintic_coefficients(x, v, a, goal_x, remaining_s), dt_s)


def stopping_goal(x, v, a, duration_s: float) -> np.ndarray:
    """Where a minimum-jerk stop from (x, v, a) in `duration_s` comes to rest if the end point is free.

    Free final position makes the quintic term vanish (natural boundary condition), which gives
    x + v T / 2 + a T^2 / 12: with a = 0 the velocity falls monotonically as v (1 - 3s^2 + 2s^3).
    """
    T = float(duration_s)
    x, v, a = (np.asarray(z, dtype=float) for z in (x, v, a))
    return x + v * (T / 2.0) + a * (T * T / 12.0)


def via_velocities(x_start, goals, durations_s) -> np.ndarray:
    """Velocities (k, n) at the ends of k sequence segments (hrpsys `setJointAnglesSequence` rule).

    At a via point: the mean of the average velocities of the segments on either side if they have the
    same sign, else 0; at the last goal: 0.
    """
    goals = np.asarray(goals, dtype=float)
    durations_s = np.asarray(durations_s, dtype=float)
    starts = np.concatenate([np.asarray(x_start, dtype=float)[None], goals[:-1]])
    avg = (goals - starts) / durations_s[:, None]
    out = np.zeros_like(goals)
    if len(goals) > 1:
        before, after = avg[:-1], avg[1:]
        out[:-1] = np.where(before * after > 0.0, 0.5 * (before + after), 0.0)
    return out


@dataclass(frozen=True)
class Segment:
    """One quintic piece: `coeffs` (6, n) over local time [0, duration_s], ending at the goal state."""

    coeffs: np.ndarray  # (6, n)
    duration_s: float  # [s]
    goal_x: np.ndarray  # (n,)
    goal_v: np.ndarray  # (n,)
    goal_a: np.ndarray  # (n,)

    @staticmethod
    def plan(x, v, a, goal_x, duration_s: float, goal_v=0.0, goal_a=0.0) -> Segment:
        coeffs = quintic_coefficients(x, v, a, goal_x, duration_s, goal_v, goal_a)
        shape = coeffs.shape[1:]
        return Segment(
            coeffs=coeffs,
            duration_s=float(duration_s),
            goal_x=np.broadcast_to(np.asarray(goal_x, dtype=float), shape).copy(),
            goal_v=np.broadcast_to(np.asarray(goal_v, dtype=float), shape).copy(),
            goal_a=np.broadcast_to(np.asarray(goal_a, dtype=float), shape).copy(),
        )

    def sample(self, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, v, a) at local time `t_s`; at or after the end, exactly the goal state."""
        if t_s >= self.duration_s:
            return self.goal_x.copy(), self.goal_v.copy(), self.goal_a.copy()
        return quintic_state(self.coeffs, t_s)

    def jerk(self, t_s: float) -> np.ndarray:
        return quintic_jerk(self.coeffs, t_s)

    def take(self, keep: np.ndarray) -> Segment:
        """The same segment restricted to the dimensions selected by `keep` (mask or indices)."""
        return Segment(self.coeffs[:, keep], self.duration_s, self.goal_x[keep], self.goal_v[keep],
                       self.goal_a[keep])


def hoff_arbib(x_from, x_to, duration_s: float) -> Segment:
    """Paper Eq. 2, x = HoffArbib(x_from, x_to, t_from->to): rest to rest; sample it with `.sample(t)`."""
    x_from = np.asarray(x_from, dtype=float)
    zeros = np.zeros_like(x_from)
    return Segment.plan(x_from, zeros, zeros, x_to, duration_s)


class HoffArbibTrack:
    """The state (x, v, a) of n dimensions and a queue of segments played from an elapsed-time cursor.

    `step(dt)` evaluates the closed form (no integration drift): each segment ends exactly on its goal.
    A new `go`/`go_sequence` replaces what remains, starting from the current state (v, a continuous).
    """

    def __init__(self, x, v=None, a=None) -> None:
        x = np.array(x, dtype=float)
        self.xva = np.zeros((3, *x.shape))  # rows: x, v, a
        self.xva[0] = x
        if v is not None:
            self.xva[1] = v
        if a is not None:
            self.xva[2] = a
        self._segments: deque[Segment] = deque()
        self._elapsed_s = 0.0  # local time in the first segment

    def __repr__(self) -> str:
        return (f"HoffArbibTrack(dim={self.x.size}, segments={len(self._segments)}, "
                f"remaining_s={self.remaining_s:.3f})")

    @property
    def x(self) -> np.ndarray:
        return self.xva[0]

    @property
    def v(self) -> np.ndarray:
        return self.xva[1]

    @property
    def a(self) -> np.ndarray:
        return self.xva[2]

    @property
    def is_moving(self) -> bool:
        return bool(self._segments)

    @property
    def remaining_s(self) -> float:
        return max(sum(s.duration_s for s in self._segments) - self._elapsed_s, 0.0)

    @property
    def segments(self) -> tuple[Segment, ...]:
        return tuple(self._segments)

    def go(self, goal_x, duration_s: float) -> None:
        """Replace the queue with one move to `goal_x` (at rest) in `duration_s`."""
        goal_x = np.broadcast_to(np.asarray(goal_x, dtype=float), self.x.shape)
        self.go_sequence(goal_x[None], [duration_s])

    def go_sequence(self, goals, durations_s) -> None:
        """Replace the queue with moves through `goals` (k, n) taking `durations_s` (k,) each.

        Via points get the hrpsys velocity (`via_velocities`) and zero acceleration; the last goal is at rest.
        """
        goals = np.asarray(goals, dtype=float).reshape(-1, self.x.size)
        durations_s = [float(d) for d in durations_s]
        vias = via_velocities(self.x, goals, durations_s)
        segments: deque[Segment] = deque()
        x, v, a = self.xva.copy()
        zeros = np.zeros_like(x)
        for goal, goal_v, T in zip(goals, vias, durations_s, strict=True):
            seg = Segment.plan(x, v, a, goal, T, goal_v, zeros)
            segments.append(seg)
            x, v, a = seg.goal_x, seg.goal_v, seg.goal_a
        self._segments = segments
        self._elapsed_s = 0.0

    def brake(self, duration_s: float) -> None:
        """Replace the queue with a minimum-jerk stop in `duration_s` (end position free, `stopping_goal`)."""
        self.go(stopping_goal(self.x, self.v, self.a, duration_s), duration_s)

    def stop(self) -> None:
        """Stop where it is now: empty queue, zero velocity and acceleration."""
        self._segments.clear()
        self._elapsed_s = 0.0
        self.xva[1:] = 0.0

    def step(self, dt_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Advance the cursor by `dt_s`; returns the new (x, v, a) (the track's own arrays: do not modify)."""
        x, v, a = self.step_xva(dt_s)
        return x, v, a

    def step_xva(self, dt_s: float) -> np.ndarray:
        """As `step`, returning the stacked (3, n) state (the track's own array: do not modify)."""
        segments = self._segments
        if not segments:
            return self.xva
        t = self._elapsed_s + dt_s
        seg = segments[0]
        while t >= seg.duration_s - END_TOLERANCE_S:
            t = max(t - seg.duration_s, 0.0)
            segments.popleft()
            if not segments:
                self._elapsed_s = 0.0
                self.xva = np.stack([seg.goal_x, seg.goal_v, seg.goal_a])
                return self.xva
            seg = segments[0]
        self._elapsed_s = t
        self.xva = quintic_xva(seg.coeffs, t)
        return self.xva

    def take(self, keep: np.ndarray) -> HoffArbibTrack:
        """A track of the dimensions selected by `keep` (mask or indices), with the same queue and cursor."""
        out = HoffArbibTrack(self.x[keep], self.v[keep], self.a[keep])
        out._segments = deque(s.take(keep) for s in self._segments)
        out._elapsed_s = self._elapsed_s
        return out
