"""The walking point's twist as the AutoBalancer's goVelocity command: speed-limited, one zero when it ends."""

from __future__ import annotations

import math

from controller.core.types import WalkCommand
from controller.operation.limits import speed_scale
from controller.operation.points import Twist


class WalkPoint:
    """Turns the walking point's summed twist into the command to publish each tick. `active`: a non-zero
    command went out (one zero follows when the twist ends); `last`: the command last published."""

    __slots__ = ("active", "last", "_key")

    def __init__(self) -> None:
        self.active = False
        self.last: WalkCommand | None = None
        self._key: tuple | None = None  # (vx, vy, vtheta, step parameters, limits) of `last`

    def command(self, twist: Twist | None, steps: WalkCommand | None, max_speed_m_s: float,
                max_turn_rad_s: float) -> WalkCommand | None:
        """The command for this tick (None: publish nothing): (vx, vy [m/s], vtheta [rad/s]) of `twist` in F,
        one scale factor for the speed [m/s] and turn [rad/s] limits, with `steps`' stride and foot distance."""
        lin, ang = (None, None) if twist is None else (twist.linear_m_s.tolist(), twist.angular_rad_s.tolist())
        if twist is None or not (any(lin) or any(ang)):  # (Twist.is_zero on the floats read once)
            if self.active:  # one zero command: the walk the operator drove stops
                self.active = False
                self.last = WalkCommand(0.0, 0.0, 0.0)
                return self.last
            return None
        vx, vy, _ = lin
        vtheta = ang[2]
        key = (vx, vy, vtheta, steps, max_speed_m_s, max_turn_rad_s)
        if key == self._key and self.active:  # the same command as last tick (a held stick)
            return self.last
        k = min(speed_scale(math.hypot(vx, vy), max_speed_m_s), speed_scale(abs(vtheta), max_turn_rad_s))
        self.last = WalkCommand(vx * k, vy * k, vtheta * k,
                                max_stride_m=steps.max_stride_m if steps else None,
                                foot_distance_m=steps.foot_distance_m if steps else None)
        self.active = True
        self._key = key
        return self.last

    def status_target(self) -> tuple[float, float, float] | None:
        """(vx, vy [m/s], vtheta [rad/s]) while a walk is driven, else None."""
        w = self.last if self.active else None
        return None if w is None else (w.vx_m_s, w.vy_m_s, w.vtheta_rad_s)
