"""The operator's streamed setpoints ([OP] xi_motion, one per operational point): a latest-value table from
the console to the robot process that never queues behind commands. The console writes the whole table
(every point's newest setpoint, each with its own sequence number) to a shared-memory board; at every tick
boundary the robot reads the board's counter, and for each point whose sequence number is new hands the
setpoint to the operation layer stamped with the control time it arrived at (the dead-man runs on it)."""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass

from app.service.board import Board
from app.service.errors import InvalidArgument, PointTaken
from controller.core.errors import InvalidCommand
from controller.core.types import WalkCommand
from controller.operation.points import POINTS, Twist
from controller.operation.ranges import check_setpoint

BOARD_BYTES = 1 << 14
STREAM_STALE_S = 0.3  # [s] of control time: a point's stream has stopped this long after its last setpoint (the
#                       dead-man's 0.2 s and its 0.1 s ramp, OperationParams' defaults: by then the point is at zero)
REMEMBERED_SEQS = 512  # per point: whose the newest setpoints were (10 s of two 25 Hz streams)


@dataclass(frozen=True, slots=True)
class Setpoint:
    """The operator's velocity for one point, in the feet frame F (controller.operation.points). Not checked here:
    a client's request by its schema (app/schemas.py), the console's own scripts' at the door (`checked`), and
    every setpoint once more by the operation layer before it moves anything (controller.operation.ranges)."""

    point: str
    linear_m_s: tuple[float, float, float]
    angular_rad_s: tuple[float, float, float]
    max_stride_m: float | None = None  # walk only: step length limit
    foot_distance_m: float | None = None  # walk only: lateral distance between the feet's centres
    seq: int = 0  # given by the console's table

    def twist(self) -> Twist:
        return Twist.of(self.linear_m_s, self.angular_rad_s)

    def is_zero(self) -> bool:
        """Every component zero: the point is told to stop."""
        return not any(self.linear_m_s) and not any(self.angular_rad_s)

    def walk(self) -> WalkCommand | None:
        if self.point != "walk":
            return None
        return WalkCommand(float(self.linear_m_s[0]), float(self.linear_m_s[1]), float(self.angular_rad_s[2]),
                           self.max_stride_m, self.foot_distance_m)


def checked(sp: Setpoint) -> Setpoint:
    """`sp` if `sp.point` takes it (controller.operation.ranges.check_setpoint), else InvalidArgument naming the
    field ("linear.x", "max_stride", ...) and the allowed range: the door's check of a setpoint made without the
    request schemas (the console's scripts, the viewer's sticks)."""
    if sp.point not in POINTS:
        raise InvalidArgument("point", f"unknown operational point {sp.point!r}; valid: {list(POINTS)}")
    for part, values in (("linear", sp.linear_m_s), ("angular", sp.angular_rad_s)):
        if len(values) != 3:
            raise InvalidArgument(part, f"give 3 components (got {len(values)})")
        for axis, v in zip("xyz", values, strict=True):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InvalidArgument(f"{part}.{axis}", f"must be a finite number (got {v!r})")
    try:
        check_setpoint(sp.point, sp.twist(), sp.max_stride_m, sp.foot_distance_m)
    except InvalidCommand as exc:
        field, _, message = str(exc).partition(": ")
        raise InvalidArgument(field.split(".", 1)[-1], message) from None
    return sp


@dataclass(frozen=True, slots=True)
class SetpointAck:
    """A setpoint reached the robot: its sequence number, the tick it was applied before, that tick's time;
    `ignored` says why it was not applied ("hard_stop": the hard e-stop was engaged; "invalid": out of the point's
    ranges, refused by the operation layer's last guard; "before_release": it was
    sent before the e-stop's release)."""

    point: str
    seq: int
    tick: int
    time_s: float
    ignored: str | None = None


@dataclass(frozen=True, slots=True)
class Sender:
    """Who put a setpoint: a display name (the client's X-Client-Id / ?client=, or "anonymous@<address>"; it
    proves nothing, the operator lock's token does) and the WebSocket stream it came on (None: a request)."""

    name: str
    stream: int | None = None

    def same_client(self, other: Sender | None) -> bool:
        """The same client: the same name, and the same stream unless one of them is a single request (a page
        that streams may also PUT; two streams are two clients, whatever they are called)."""
        return (other is not None and self.name == other.name
                and (self.stream is None or other.stream is None or self.stream == other.stream))


class PointClaims:
    """Console side, without the operator lock: the first client streaming to a point owns it until its stream
    stops (`stale_s` [s] of control time without a new setpoint, as the dead-man counts; a zero sent; or its
    WebSocket closed); another client's setpoint to it is refused (PointTaken naming the owner) rather than
    mixed in. Also remembers whose each recent setpoint was, so that an acknowledgement of a newer one can say
    whose it was. `now_s`: the robot's control time as last published. Not thread-safe: the service holds its
    lock around `claim`, the board's put and `record`."""

    def __init__(self, stale_s: float = STREAM_STALE_S, remembered: int = REMEMBERED_SEQS) -> None:
        self.stale_s = float(stale_s)
        self._remembered = int(remembered)
        self._owners: dict[str, tuple[Sender, float]] = {}  # point -> (owner, control time of its last setpoint)
        self._senders: dict[str, OrderedDict[int, Sender | None]] = {}  # point -> seq -> who put it

    def __repr__(self) -> str:
        return f"PointClaims(stale_s={self.stale_s:g}, owners={ {p: o.name for p, (o, _) in self._owners.items()} })"

    def owner(self, point: str, now_s: float) -> Sender | None:
        """The client streaming to `point` at control time `now_s` [s], or None."""
        held = self._owners.get(point)
        if held is None:
            return None
        if not 0.0 <= now_s - held[1] < self.stale_s:  # stopped (or the simulation was reset since)
            del self._owners[point]
            return None
        return held[0]

    def claim(self, sp: Setpoint, sender: Sender | None, now_s: float, override: bool = False) -> None:
        """PointTaken if another client streams to `sp.point` (unless `override`: the operator lock's holder).
        Otherwise `sender` owns the point from now (a zero gives it up); None (the console's own scripts) claims
        nothing."""
        if sender is None:
            return
        owner = self.owner(sp.point, now_s)
        if owner is not None and not override and not sender.same_client(owner):
            raise PointTaken(sp.point, owner.name,
                             f"point: {sp.point!r} is being streamed by {owner.name!r}; its setpoints are not mixed "
                             f"with another client's: wait until its stream stops ({self.stale_s:g} s after its "
                             "last setpoint, a zero, or its socket closed), choose another point, or take the "
                             "operator lock (POST /api/operator/lock)")
        if sp.is_zero():
            self._owners.pop(sp.point, None)
        else:  # a request of the streaming client's name leaves the point to that stream
            keep = owner if owner is not None and sender.stream is None and sender.same_client(owner) else sender
            self._owners[sp.point] = (keep, now_s)

    def record(self, numbered: Setpoint, sender: Sender | None) -> None:
        """`numbered` (as the table numbered it) was put by `sender`."""
        seen = self._senders.setdefault(numbered.point, OrderedDict())
        seen[numbered.seq] = sender
        while len(seen) > self._remembered:
            seen.popitem(last=False)

    def sender_of(self, point: str, seq: int) -> Sender | None:
        """Who put setpoint `seq` of `point` (None: the console's own, or too old to remember)."""
        seen = self._senders.get(point)
        return None if seen is None else seen.get(seq)

    def release(self, stream: int) -> list[str]:
        """The stream `stream` closed: the points it owned are free; they are returned."""
        points = [p for p, (o, _) in self._owners.items() if o.stream == stream]
        for p in points:
            del self._owners[p]
        return points


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
            # numbered, the components as floats (not checked again: see Setpoint)
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
        try:  # one try: the loop never waits for the console's writer (a torn read is taken next tick)
            table = self.board.get(retries=1, stale_ok=False)
        except TimeoutError:
            return None
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
