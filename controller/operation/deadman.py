"""The streamed setpoint's dead-man: a setpoint older than the timeout counts as zero, reached by a ramp."""

from __future__ import annotations

from controller.core.errors import InvalidCommand
from controller.operation.points import Twist

DEADMAN_TIMEOUT_S = 0.2  # a setpoint older than this [s] of control time no longer counts in full
DEADMAN_RAMP_S = 0.1  # ... and fades to zero over this [s] after the timeout, instead of snapping


def deadman_factor(age_s: float, timeout_s: float = DEADMAN_TIMEOUT_S, ramp_s: float = DEADMAN_RAMP_S) -> float:
    """The weight [0, 1] of a setpoint `age_s` [s] old: 1 up to `timeout_s`, then linearly down to 0 over
    `ramp_s` (0 from timeout_s + ramp_s on; ramp_s = 0 snaps). A setpoint from the future (age < 0) counts."""
    if timeout_s < 0.0 or ramp_s < 0.0:
        raise InvalidCommand(f"deadman timeout_s={timeout_s}, ramp_s={ramp_s}: both must be >= 0 [s]")
    over = age_s - timeout_s
    if over <= 0.0:
        return 1.0
    if over >= ramp_s - 1e-12:  # (0.3 - 0.2 is a hair under 0.1 in floats)
        return 0.0
    return 1.0 - over / ramp_s


def live_twists(setpoints: dict[str, tuple[Twist, float]], time_s: float, timeout_s: float = DEADMAN_TIMEOUT_S,
                ramp_s: float = DEADMAN_RAMP_S, ramping: set[str] | None = None) -> dict[str, Twist]:
    """The streamed setpoints {point: (twist, control time it arrived [s])} as they count at `time_s` [s]: each
    twist weighted by deadman_factor of its age; a setpoint whose weight reached 0 is removed from `setpoints`.
    The points past the timeout but not faded out yet are added to `ramping` (when given)."""
    out = {}
    for point, (twist, t0) in list(setpoints.items()):
        if time_s - t0 <= timeout_s and timeout_s >= 0.0 and ramp_s >= 0.0:  # fresh
            out[point] = twist
            continue
        k = deadman_factor(time_s - t0, timeout_s, ramp_s)
        if k <= 0.0:
            del setpoints[point]
            continue
        out[point] = twist if k == 1.0 else twist.scaled(k)
        if ramping is not None and k < 1.0:
            ramping.add(point)
    return out


class StreamedSetpoints:
    """The operator's latest setpoint per point with the control time it arrived [s], and the walking point's
    step parameters; `live(time_s, ...)` is what counts of them at that time under the dead-man."""

    __slots__ = ("_setpoints", "walk_steps", "ramping")

    def __init__(self) -> None:
        self._setpoints: dict[str, tuple[Twist, float]] = {}
        self.walk_steps = None  # the walking point's step parameters (a WalkCommand), kept past a drop
        #: the points the last `live` found past the dead-man's timeout, fading out (replaced, never changed: a
        #: status may hold it)
        self.ramping: frozenset[str] = frozenset()

    def __bool__(self) -> bool:
        return bool(self._setpoints)

    def set(self, point: str, twist: Twist, time_s: float, walk_steps=None) -> None:
        """`twist` (checked by the caller) for `point`, arrived at control time `time_s` [s]."""
        self._setpoints[point] = (twist, float(time_s))
        if point == "walk":
            self.walk_steps = walk_steps

    def clear(self) -> bool:
        """Forget every setpoint; whether there was one."""
        had = bool(self._setpoints)
        self._setpoints.clear()
        return had

    def live(self, time_s: float, timeout_s: float = DEADMAN_TIMEOUT_S,
             ramp_s: float = DEADMAN_RAMP_S) -> dict[str, Twist]:
        """The setpoints as they count at `time_s` [s] (live_twists); the faded-out ones are forgotten."""
        if not self._setpoints:
            self.ramping = _NONE
            return {}
        ramping: set[str] = set()
        out = live_twists(self._setpoints, time_s, timeout_s, ramp_s, ramping)
        self.ramping = frozenset(ramping) if ramping else _NONE
        return out


_NONE: frozenset[str] = frozenset()
