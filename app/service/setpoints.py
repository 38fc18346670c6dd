"""The operator's streamed setpoints ([OP] xi_motion, one per operational point): a latest-value table from
the console to the robot process that never queues behind commands. The console writes the whole table
(every point's newest setpoint, each with its own sequence number) to a shared-memory board; at every tick
boundary the robot reads the board's counter, and for each point whose sequence number is new hands the
setpoint to the operation layer stamped with the control time it arrived at (the dead-man runs on it)."""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping
from dataclasses import dataclass

from app.service.board import Board
from app.service.errors import InvalidArgument
from controller.core.errors import InvalidCommand
from controller.operation.points import POINTS, Twist, WalkCommand, check_twist

MAX_LINEAR_M_S = 0.5  # [m/s] |component| of a streamed linear velocity (the op layer limits further)
MAX_ANGULAR_RAD_S = math.radians(90.0)  # [rad/s] |component| of a streamed angular velocity
MAX_STRIDE_RANGE_M = (0.01, 0.5)  # [m] the walking point's step length limit
FOOT_DISTANCE_RANGE_M = (0.12, 0.4)  # [m] the walking point's distance between the feet's centres
BOARD_BYTES = 1 << 14


@dataclass(frozen=True, slots=True)
class Setpoint:
    """The operator's velocity for one point, in the feet frame F (controller.operation.points)."""

    point: str
    linear_m_s: tuple[float, float, float]
    angular_rad_s: tuple[float, float, float]
    max_stride_m: float | None = None  # walk only: step length limit
    foot_distance_m: float | None = None  # walk only: lateral distance between the feet's centres
    seq: int = 0  # given by the console's table

    def __post_init__(self) -> None:
        if self.point not in POINTS:
            raise InvalidArgument("point", f"unknown operational point {self.point!r}; valid: {list(POINTS)}")
        for part, values, limit, unit, shown in (
                ("linear", self.linear_m_s, MAX_LINEAR_M_S, "m/s", float),
                ("angular", self.angular_rad_s, MAX_ANGULAR_RAD_S, "deg/s", math.degrees)):
            if len(values) != 3:
                raise InvalidArgument(part, f"give 3 components (got {len(values)})")
            for axis, v in zip("xyz", values, strict=True):
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise InvalidArgument(f"{part}.{axis}", f"must be a finite number (got {v!r})")
                if abs(v) > limit + 1e-12:
                    raise InvalidArgument(f"{part}.{axis}", f"{shown(v):g} {unit} is outside the allowed range "
                                                            f"[{-shown(limit):g}, {shown(limit):g}] {unit}")
        try:
            check_twist(self.point, self.twist())
        except InvalidCommand as exc:
            field, _, message = str(exc).partition(": ")
            raise InvalidArgument(field.split(".", 1)[-1] if "." in field else field, message) from None
        for name, value, (lo, hi) in (("max_stride", self.max_stride_m, MAX_STRIDE_RANGE_M),
                                      ("foot_distance", self.foot_distance_m, FOOT_DISTANCE_RANGE_M)):
            if value is None:
                continue
            if self.point != "walk":
                raise InvalidArgument(name, "is a parameter of the walking point only (point 'walk')")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
                raise InvalidArgument(name, f"{value!r} m is outside the allowed range [{lo:g}, {hi:g}] m")

    def twist(self) -> Twist:
        return Twist.of(self.linear_m_s, self.angular_rad_s)

    def walk(self) -> WalkCommand | None:
        if self.point != "walk":
            return None
        return WalkCommand(float(self.linear_m_s[0]), float(self.linear_m_s[1]), float(self.angular_rad_s[2]),
                           self.max_stride_m, self.foot_distance_m)


@dataclass(frozen=True, slots=True)
class SetpointAck:
    """A setpoint reached the robot: its sequence number, the tick it was applied before, that tick's time;
    `ignored` says why it was not applied ("hard_stop": the hard e-stop was engaged; "before_release": it was
    sent before the e-stop's release)."""

    point: str
    seq: int
    tick: int
    time_s: float
    ignored: str | None = None


class SetpointTable:
    """Console side: the newest setpoint of every point, numbered; `publish(table)` is where it goes (a
    Board's put, or a robot in this process). Thread-safe (HTTP handlers and WebSockets share it)."""

    def __init__(self, publish) -> None:
        self._publish = publish
        self._lock = threading.Lock()
        self._seq = 0
        self._table: dict[str, Setpoint] = {}

    def put(self, sp: Setpoint) -> Setpoint:
        with self._lock:
            self._seq += 1
            numbered = Setpoint(sp.point, tuple(map(float, sp.linear_m_s)), tuple(map(float, sp.angular_rad_s)),
                                sp.max_stride_m, sp.foot_distance_m, self._seq)
            self._table[sp.point] = numbered
            self._publish(dict(self._table))
            return numbered

    @property
    def last_seq(self) -> int:
        """The newest sequence number given (0: none yet)."""
        return self._seq


class BoardSource:
    """Robot side of the board: `poll()` gives the table when the board changed since the last poll (one
    integer read otherwise)."""

    def __init__(self, board: Board) -> None:
        self.board = board
        self._version = 0

    def poll(self) -> Mapping[str, Setpoint] | None:
        v = self.board.version()
        if v == self._version or v % 2:
            return None
        table = self.board.get()
        self._version = v
        return table


class LocalSource:
    """The same for a robot in this process: the table handed over under a lock."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._table: Mapping[str, Setpoint] | None = None

    def put(self, table: Mapping[str, Setpoint]) -> None:
        with self._lock:
            self._table = table

    def poll(self) -> Mapping[str, Setpoint] | None:
        with self._lock:
            table, self._table = self._table, None
        return table
