"""The hard e-stop's one semantics, used by every way in (POST /api/estop, the stick stream, the robot's e-stop
door, the viser button, the bench): what an e-stop message is, what a press id is, and when a press engages.

The rule: a press engages the stop unless it is engaged already; an answer that says ok means the loop has the
stop engaged. The only press that does not engage is a late copy: the page sends each press three ways with one
id, and a copy that arrives after the operator has released that very press, within COPY_WINDOW_S of the press's
first copy, is answered `late_copy` and changes nothing. After the window the same id engages again, so a script
or a button bridge that always sends one id is never answered ok without a stop. A malformed id never blocks a
stop: the press engages, the answer says the id was ignored."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass

COPY_WINDOW_S = 0.5  # [s] the copies of one press (three sockets, sent at once) arrive within this of the first
ESTOP_PRESS_PATTERN = r"^[A-Za-z0-9_.:-]{1,64}$"
PRESS_RULE = "1 to 64 characters of A-Z a-z 0-9 _ . : - (one id per press, the same on each way it is sent)"
_PRESS = re.compile(ESTOP_PRESS_PATTERN)


def press_error(press: object) -> str | None:
    """What is wrong with `press` as a press id (None: nothing; no id is allowed)."""
    if press is None or (isinstance(press, str) and _PRESS.match(press)):
        return None
    return f"press: {PRESS_RULE}"


@dataclass(frozen=True)
class EstopRequest:
    """One e-stop as a client sent it: its press id (None: none, or a malformed one, said in `press_ignored`)."""

    press: str | None = None
    press_ignored: str | None = None  # why the given id was not used (the stop engages all the same)


def request_of(press: object) -> EstopRequest:
    """The e-stop for a press id as given (a header's or a message's)."""
    why = press_error(press)
    return EstopRequest(None, why) if why is not None else EstopRequest(press)  # type: ignore[arg-type]


def parse_message(message: object) -> EstopRequest | None:
    """Decoded JSON as an e-stop: any object whose "estop" is true, whatever its spelling or key order, its
    "press" the id; None: not an e-stop."""
    if isinstance(message, dict) and message.get("estop") is True:
        return request_of(message.get("press"))
    return None


def parse_text(data: str | bytes) -> EstopRequest | None:
    """A text frame as an e-stop (None: not JSON, or not an e-stop). Never raises."""
    try:
        return parse_message(json.loads(data))
    except (ValueError, RecursionError, UnicodeDecodeError, TypeError):
        return None


class PressLog:
    """The presses of the last COPY_WINDOW_S, each with the answer to its first copy, and the last release: whether
    another copy of a press is a late one (the operator released that press since). Times in seconds of one
    monotonic clock."""

    def __init__(self, window_s: float = COPY_WINDOW_S) -> None:
        self.window_s = float(window_s)
        self._first: dict[str, EstopAck] = {}  # press id -> the answer to its first copy
        self._released_at_s = float("-inf")
        self._last_press_s = float("-inf")  # when the newest press (not a copy) was handled

    def first(self, press: str | None, now_s: float) -> EstopAck | None:
        """The answer to the first copy of `press`, if it came within the window."""
        ack = None if press is None else self._first.get(press)
        return ack if ack is not None and now_s - ack.engaged_at_monotonic_s < self.window_s else None

    def released_after(self, ack: EstopAck) -> bool:
        return self._released_at_s >= ack.engaged_at_monotonic_s

    def pressed(self, press: str | None, ack: EstopAck) -> None:
        """`ack` answered a copy of `press`: kept if it is the first of the window."""
        now_s = ack.engaged_at_monotonic_s
        self._last_press_s = max(self._last_press_s, now_s)
        self._first = {p: a for p, a in self._first.items() if now_s - a.engaged_at_monotonic_s < self.window_s}
        if press is not None:
            self._first.setdefault(press, ack)

    def released(self, now_s: float) -> None:
        self._released_at_s = now_s

    def pressed_since(self, sent_s: float) -> bool:
        """Whether a press (not a copy of an earlier one) was handled after `sent_s`: a release sent then must not
        release the stop it engaged."""
        return self._last_press_s > sent_s


@dataclass(frozen=True)
class EstopAck:
    """What the loop did with an e-stop: `engaged` is the loop's own state after it (True for every press but a
    late copy); the tick, the simulation time and the monotonic time it was handled at."""

    tick: int
    sim_time_s: float
    engaged_at_monotonic_s: float
    engaged: bool
    already_engaged: bool = False
    late_copy: bool = False
    copy: bool = False  # another copy of a press that engaged the stop, still engaged: the first copy's answer
    press_ignored: str | None = None

    @property
    def message(self) -> str:
        if self.copy:
            return "hard e-stop engaged (by another copy of this press)"
        if self.late_copy:
            return (f"a late copy of a press already released: not engaged again (the same press id engages "
                    f"again {COPY_WINDOW_S:g} s after its first copy)")
        return "hard e-stop already engaged" if self.already_engaged else "hard e-stop engaged"

    def reply(self, via: str | None = None) -> dict:
        """The answer every way in gives (POST /api/estop's EstopResponse): ok only when engaged."""
        body = {"ok": self.engaged, "engaged": self.engaged, "message": self.message, "tick": self.tick,
                "sim_time_s": self.sim_time_s, "engaged_at_monotonic_s": self.engaged_at_monotonic_s,
                "late_copy": self.late_copy, "copy": self.copy}
        if not self.engaged:
            body["reason"] = "late_copy"
        if self.press_ignored is not None:
            body["press_ignored"] = self.press_ignored
        if via is not None:
            body["via"] = via
        return body
