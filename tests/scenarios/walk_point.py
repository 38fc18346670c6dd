"""The operator's walking point through the real operation layer: a WalkCommand (or None) streamed into
`op.set_motion("walk", ...)` at every tick boundary, as the operator console streams its stick, optionally
with the hands and the head moved at the same time."""

from __future__ import annotations

import math
from collections.abc import Callable

from controller.core.types import WalkCommand
from controller.operation.points import Twist


class OperatorWalk:
    """Streams `command` into the op layer before every step of `loop` (None: the stick released, a zero
    setpoint: op sends the AutoBalancer one zero command and then leaves the port alone). `also`, if set,
    is called with (op, control time) before each step for the other points."""

    def __init__(self, loop) -> None:
        self.loop = loop
        self.op = loop.chain["op"]
        self.command: WalkCommand | None = None
        self.also: Callable[[object, float], None] | None = None
        inner = loop.step

        def step(*args, **kwargs):
            self._stream()
            return inner(*args, **kwargs)

        loop.step = step  # Walker.run steps through this (loop.run_for does not: it streams nothing)

    def _stream(self) -> None:
        t = self.loop.plant.time_s
        cmd = self.command
        if cmd is None:
            self.op.set_motion("walk", Twist.of(), t)
        else:
            steps = cmd if (cmd.max_stride_m is not None or cmd.foot_distance_m is not None) else None
            self.op.set_motion("walk", Twist.of((cmd.vx_m_s, cmd.vy_m_s, 0.0), (0.0, 0.0, cmd.vtheta_rad_s)), t,
                               walk=steps)
        if self.also is not None:
            self.also(self.op, t)


def hands_and_head(op, t: float) -> None:
    """The operator's other stick: both hands on slow 5 cm circles (0.05 m/s), the head sweeping 20 deg/s
    (the same stream as `hrp2-console bench --scenario teleop`)."""
    c, s = math.cos(t), math.sin(t)
    op.set_motion("rhand", Twist.of((0.05 * c, 0.0, 0.05 * s)), t)
    op.set_motion("lhand", Twist.of((0.05 * c, 0.0, -0.05 * s)), t)
    op.set_motion("head", Twist.of(angular_rad_s=(0.0, 0.0, math.radians(20.0) * c)), t)


def install(loop) -> OperatorWalk:
    return OperatorWalk(loop)
