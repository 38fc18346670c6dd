"""Replay: a recorded session's inputs fed again, each at the tick it took effect at, into a fresh simulation
(same scene, start parameters, control period) run as fast as possible; every tick's log row and the digest of
the simulator's whole configuration are compared with the recording, bit for bit (the determinism contract:
same inputs, same trajectory, paced or not). The first difference is reported with what differs."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.service.errors import ServiceError
from app.service.log_row import COLUMNS
from app.service.verbs import ReleaseEstop
from app.session.inputs import BadInput, decode, outcome_of, same_outcome
from app.session.reader import Session
from app.session.writer import qpos_digest

#: columns shown in a difference's text, at most
SHOWN_COLUMNS = 8


class NotReplayable(ValueError):
    """The session cannot be replayed: why, and from which tick."""


@dataclass
class Difference:
    """The first tick where the replay left the recording."""

    tick: int
    time_s: float
    what: str  # "row", "sim_digest" or "input"
    detail: str
    columns: list[str] = field(default_factory=list)  # every column that differs (row), in row order
    recorded: list[float] = field(default_factory=list)
    replayed: list[float] = field(default_factory=list)

    def __str__(self) -> str:
        text = f"tick {self.tick} (t = {self.time_s:.3f} s), {self.what}: {self.detail}"
        if self.columns:
            shown = list(zip(self.columns, self.recorded, self.replayed, strict=True))[:SHOWN_COLUMNS]
            pairs = ", ".join(f"{c} {r!r} -> {p!r}" for c, r, p in shown)
            more = len(self.columns) - len(shown)
            text += f" [{pairs}{f', and {more} more' if more else ''}]"
        return text


@dataclass
class ReplayResult:
    ticks: int  # ticks replayed and compared
    recorded_ticks: int
    inputs: int  # inputs applied
    wall_s: float
    sim_s: float
    difference: Difference | None

    @property
    def identical(self) -> bool:
        return self.difference is None and self.ticks == self.recorded_ticks

    def summary(self) -> dict[str, Any]:
        return {"identical": self.identical, "ticks": self.ticks, "recorded_ticks": self.recorded_ticks,
                "inputs": self.inputs, "sim_time_s": round(self.sim_s, 6), "wall_time_s": round(self.wall_s, 3),
                "real_time_factor": round(self.sim_s / self.wall_s, 2) if self.wall_s > 0 else None,
                "first_difference": None if self.difference is None else str(self.difference)}


class ReplaySource:
    """Stands in for the operator's setpoint board: gives, at the start of a tick, the setpoints the recording
    took there (their "hook" inputs)."""

    def __init__(self) -> None:
        self._table: dict | None = None

    def put(self, setpoints) -> None:
        table = self._table if self._table is not None else {}
        for sp in setpoints:
            table[sp.point] = sp
        self._table = table

    def poll(self):
        table, self._table = self._table, None
        return table


def same_bits(recorded: np.ndarray, replayed: np.ndarray) -> np.ndarray:
    """Per element: equal to the bit (0.0 and -0.0 differ), NaN equal to NaN (the file writes it as null)."""
    both_nan = np.isnan(recorded) & np.isnan(replayed)
    return both_nan | ((recorded == replayed) & (np.signbit(recorded) == np.signbit(replayed)))


def replay(session: Session, on_tick: Callable[[int], None] | None = None, stop_at_difference: bool = True
           ) -> ReplayResult:
    """Run the session's inputs through a fresh simulation and compare every tick. `on_tick(k)` is called
    after tick k (progress)."""
    from app.service.local import LocalRobot

    if not session.is_session:
        raise NotReplayable("a DataLogger export holds no inputs: only a session can be replayed")
    h = session.header
    if session.first_tick != 0:
        raise NotReplayable(f"the file's first whole tick is {session.first_tick}, not 0")
    bad = next((d for d in session.inputs if not d.get("replayable", True)), None)
    if bad is not None and int(bad["tick"]) < session.ticks:
        raise NotReplayable(f"input {bad['name']!r} at tick {bad['tick']} was not recorded in a form a replay can "
                            f"apply ({bad['input']}); the replay could only go as far as that tick")
    robot = LocalRobot(scene=h["scene"], speed=None, dt_control_s=float(h["dt_control_s"]),
                       start_auto_balancer=bool(h.get("start_auto_balancer", True)),
                       params=h.get("startup_params") or None)
    try:
        return _run(session, robot, on_tick, stop_at_difference)
    finally:
        robot.close()


def _run(session: Session, robot, on_tick, stop_at_difference: bool) -> ReplayResult:
    host = robot.host
    h = session.header
    if h.get("start") == "reset":
        host.runner.continue_ids_from(int(h["next_run_id"]))
    source = ReplaySource()
    host.setpoints = source
    host.replayed_captures = {}
    by_tick: dict[int, list[dict]] = {}
    for doc in session.inputs:
        by_tick.setdefault(int(doc["tick"]), []).append(doc)
    applied = 0
    difference: Difference | None = None
    wall0 = time.perf_counter()
    ticks = 0
    for k in range(session.ticks):
        for doc in by_tick.get(k, ()):
            applied += 1
            problem = _apply(host, source, doc)
            if problem is not None and difference is None:
                difference = Difference(k, float(doc["time_s"]), "input", problem)
        if difference is not None and stop_at_difference:
            break
        robot.step()
        ticks = k + 1
        if difference is None:
            difference = _compare(session, host, k)
        if on_tick is not None:
            on_tick(k)
        if difference is not None and stop_at_difference:
            break
    wall_s = time.perf_counter() - wall0
    return ReplayResult(ticks=ticks, recorded_ticks=session.ticks, inputs=applied, wall_s=wall_s,
                        sim_s=ticks * session.dt_s, difference=difference)


def _apply(host, source: ReplaySource, doc: Mapping[str, Any]) -> str | None:
    """Apply one recorded input as the recording did; what went differently, or None."""
    kind, recorded = doc["kind"], doc.get("outcome", {})
    try:
        value = decode(doc["input"])
    except BadInput as exc:
        return f"input {doc.get('name')!r} does not rebuild: {exc}"
    if kind == "estop":
        host.engage_estop()
        return None
    if kind == "capture":  # a result the recording took late: held until the boundary it entered at
        host.replayed_captures[int(value)] = doc["name"]
        return None
    if kind == "setpoints":
        if doc["phase"] == "hook":
            source.put(value)  # taken by the tick's own start, as recorded
            return None
        acks = host.apply_setpoints({sp.point: sp for sp in value}, float(doc["time_s"]))
        got = [[a.point, a.seq, a.ignored] for a in acks]
        if got != recorded.get("acks", got):
            return f"setpoints acknowledged {got}, recorded {recorded['acks']}"
        return None
    if isinstance(value, ReleaseEstop):  # its sent time is of the recorded run's clock, not this one's
        if recorded.get("ok") is False and recorded.get("reason") == "hard_stop":
            return None  # refused for a press after it was sent: it changed nothing
        value = dataclasses.replace(value, sent_monotonic_s=None)
    try:
        outcome = outcome_of(host.apply(value))
    except ServiceError as exc:
        outcome = outcome_of(error=exc)
    if not same_outcome(recorded, outcome):
        return (f"verb {doc['name']!r}: recorded {_said(recorded)}, replayed {_said(outcome)}")
    return None


def _said(outcome: Mapping[str, Any]) -> str:
    if outcome.get("ok"):
        return "ok"
    return f"{outcome.get('error')} ({outcome.get('reason', '-')}): {outcome.get('message', '')}"


def _compare(session: Session, host, k: int) -> Difference | None:
    recorded = session.rows[k]
    replayed = host.logger.last_row()
    same = same_bits(recorded, replayed)
    if not same.all():
        idx = np.flatnonzero(~same)
        return Difference(k, float(recorded[0]), "row", f"{int((~same).sum())} of {len(same)} columns differ",
                          [COLUMNS[i] for i in idx], recorded[idx].tolist(), replayed[idx].tolist())
    digest = session.digests[k]
    if digest is not None:
        got = qpos_digest(host.observation.truth.qpos)
        if got != digest:
            return Difference(k, float(recorded[0]), "sim_digest", f"the simulator's qpos digest is {got}, "
                                                                   f"recorded {digest} (the log row is the same)")
    return None

