"""Reading a session file back: its header, its inputs in the order they took effect, and the log rows rebuilt
bit for bit from the JSON channels. The file is read as a stream, record by record, so a file whose writer was
killed (no summary, no footer, maybe half a chunk at its end) is read up to its last complete tick."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mcap.records import Channel, Footer, Message, Metadata
from mcap.stream_reader import StreamReader

from app.service.log_row import COLUMNS, ROW_LENGTH, TICK_TOPICS
from app.session.channels import (
    BEHAVIORS_TOPIC,
    DIGEST_TOPIC,
    INPUTS_TOPIC,
    LOG_METADATA,
    PARAMS_TOPIC,
    ROW_TOPICS,
    SESSION_METADATA,
    fill_from_message,
)


class NotASession(ValueError):
    """The file is not a session (or a log) this console wrote: what it is instead."""


@dataclass
class Session:
    """What a session file holds (or a DataLogger export: no inputs, no digests)."""

    path: Path | None
    header: dict[str, Any]
    rows: np.ndarray  # (ticks, ROW_LENGTH): the log row after each tick
    digests: list[str | None]  # per tick: the simulator's qpos digest (None in a log export)
    inputs: list[dict] = field(default_factory=list)  # the /session/inputs messages, in the order applied
    params: list[dict] = field(default_factory=list)
    behaviors: list[dict] = field(default_factory=list)
    complete: bool = True  # the file was finished (summary and footer); false: read up to its last full tick
    problem: str | None = None  # why the reading stopped early
    first_tick: int = 0
    kind: str = "session"  # or "log" (a DataLogger export)

    @property
    def ticks(self) -> int:
        return len(self.rows)

    @property
    def dt_s(self) -> float:
        return float(self.header.get("dt_control_s", 0.005))

    @property
    def is_session(self) -> bool:
        return self.kind == "session"

    def __repr__(self) -> str:
        where = self.path.name if self.path is not None else "<memory>"
        return (f"Session({where!r}, ticks={self.ticks}, inputs={len(self.inputs)}, complete={self.complete}, "
                f"scene={self.header.get('scene')!r})")


def _records(stream, session: Session):
    """The stream's records; stops (and says why) at a truncated or damaged end."""
    reader = StreamReader(stream, record_size_limit=1 << 30)
    try:
        yield from reader.records
    except Exception as exc:  # noqa: BLE001 - a killed writer leaves any kind of partial record at the end
        session.complete = False
        session.problem = f"{type(exc).__name__}: {exc}"


def read_session(path: str | Path) -> Session:
    """Read a session file (or a DataLogger export); NotASession when it is neither."""
    path = Path(path)
    with open(path, "rb") as f:
        return read_stream(f, path)


def read_stream(stream, path: Path | None = None) -> Session:
    session = Session(path, {}, np.empty((0, ROW_LENGTH)), [], complete=False)
    channels: dict[int, str] = {}
    per_tick: dict[int, dict[str, Any]] = {}
    try:
        for record in _records(stream, session):
            if isinstance(record, Metadata) and record.name in (SESSION_METADATA, LOG_METADATA):
                session.header = {k: json.loads(v) for k, v in record.metadata.items()}
                session.kind = "session" if record.name == SESSION_METADATA else "log"
            elif isinstance(record, Channel):
                channels[record.id] = record.topic
            elif isinstance(record, Message):
                topic = channels.get(record.channel_id)
                if topic is None:
                    continue
                doc = json.loads(record.data)
                if topic == INPUTS_TOPIC:
                    session.inputs.append(doc)
                elif topic == PARAMS_TOPIC:
                    session.params.append(doc)
                elif topic == BEHAVIORS_TOPIC:
                    session.behaviors.append(doc)
                elif topic in ROW_TOPICS or topic == DIGEST_TOPIC:
                    per_tick.setdefault(int(doc["tick"]), {})[topic] = doc
            elif isinstance(record, Footer):
                session.complete = session.problem is None
    except (OSError, ValueError) as exc:
        session.complete = False
        session.problem = f"{type(exc).__name__}: {exc}"
    if not session.header:
        raise NotASession(f"{path}: no {SESSION_METADATA!r} or {LOG_METADATA!r} metadata: not a session or a log "
                          "written by hrp2-console")
    columns = session.header.get("columns")
    if columns is not None and list(columns) != list(COLUMNS):
        raise NotASession(f"{path}: written with another row layout ({len(columns)} columns, this console has "
                          f"{ROW_LENGTH}): replay it with the version that recorded it")
    _rebuild_rows(session, per_tick)
    return session


def _rebuild_rows(session: Session, per_tick: Mapping[int, Mapping[str, Any]]) -> None:
    """The rows of the ticks that are whole (every tick topic there), from the first one on, in order; the
    on-change topics carry their last value forward."""
    if not per_tick:
        return
    needed = set(TICK_TOPICS) | ({DIGEST_TOPIC} if session.is_session else set())
    first = min(per_tick)
    session.first_tick = first
    rows, digests = [], []
    row = np.full(ROW_LENGTH, np.nan)
    tick = first
    while tick in per_tick and needed <= set(per_tick[tick]):
        messages = per_tick[tick]
        row = row.copy()
        for topic in ROW_TOPICS:
            doc = messages.get(topic)
            if doc is not None:
                fill_from_message(row, topic, doc)
        row[0] = messages[TICK_TOPICS[0]]["time_s"]
        rows.append(row)
        digest = messages.get(DIGEST_TOPIC)
        digests.append(None if digest is None else digest["qpos_blake2b"])
        tick += 1
    if tick in per_tick or any(t > tick for t in per_tick):
        session.complete = False
        session.problem = session.problem or f"tick {tick} is not whole in the file"
    session.rows = np.array(rows) if rows else np.empty((0, ROW_LENGTH))
    session.digests = digests
    # inputs after the last whole tick cannot be replayed against anything: keep them, the replay stops there
    session.inputs.sort(key=lambda d: int(d["tick"]))  # stable: the order within a tick is the order applied
