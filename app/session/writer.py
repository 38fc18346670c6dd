"""The session writer: a process of its own that turns the recorder's batches (rows, the simulator's qpos, the
inputs and events of some ticks) into MCAP messages and flushes the file after each batch. It finishes the file
(summary, footer) on the recorder's end marker, or when the process that records has died.

It imports no simulation and no controller: numpy, mcap and the channel definitions only."""

from __future__ import annotations

import hashlib
import logging
import signal
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

from app.session.channels import DIGEST_TOPIC, SESSION_METADATA
from app.session.mcap_log import McapLog, time_ns

log = logging.getLogger(__name__)


@dataclass
class Batch:
    """The recorder's ticks [first_tick, first_tick + len(rows)) and the events up to the next tick boundary.

    `events`: (tick, topic, message) in the order they happened; an input at tick k took effect before the
    k-th recorded tick (at the boundary after tick k - 1)."""

    first_tick: int
    rows: np.ndarray  # (n, ROW_LENGTH)
    qpos: Sequence[np.ndarray]  # n arrays (nq,): the simulator's configuration after each tick
    events: list[tuple[int, str, dict]] = field(default_factory=list)


def qpos_digest(qpos: np.ndarray) -> str:
    """8 bytes of BLAKE2b over the float64 bytes of qpos, as hex."""
    return hashlib.blake2b(np.ascontiguousarray(qpos, dtype=np.float64).tobytes(), digest_size=8).hexdigest()


class SessionFile:
    """An open session file: the header as metadata, then batches."""

    def __init__(self, path: str, header: Mapping[str, Any]) -> None:
        self.dt_s = float(header["dt_control_s"])
        self.log = McapLog(path, SESSION_METADATA, header, session=True)
        self.ticks = 0

    def write(self, batch: Batch) -> None:
        log_ = self.log
        events = iter(batch.events)
        pending = next(events, None)
        for i, row in enumerate(batch.rows):
            tick = batch.first_tick + i
            while pending is not None and pending[0] <= tick:
                log_.write(pending[1], time_ns(pending[0] * self.dt_s), pending[2])
                pending = next(events, None)
            t_ns = time_ns((tick + 1) * self.dt_s)  # the state after the tick
            log_.write_row(tick, t_ns, row)
            q = batch.qpos[i]
            log_.write(DIGEST_TOPIC, t_ns, {"tick": tick, "time_s": float(row[0]), "qpos_blake2b": qpos_digest(q),
                                            "nq": int(len(q))})
            self.ticks = tick + 1
        while pending is not None:
            log_.write(pending[1], time_ns(pending[0] * self.dt_s), pending[2])
            pending = next(events, None)
        log_.flush()

    def finish(self) -> None:
        self.log.finish()


def writer_main(path: str, header: Mapping[str, Any], batches: Connection) -> None:
    """The process's main: write batches until the pipe ends (the recorder closed it, or its process died: this
    process holds only the reading end, so either way the end of the pipe is read)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the recorder decides
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s session-writer %(name)s: %(message)s")
    out = SessionFile(path, header)
    try:
        while True:
            try:
                batch = batches.recv()
            except EOFError:
                break
            except Exception as exc:  # noqa: BLE001 - a batch cut short by the recorder's death
                log.error("%s: the last batch could not be read (%s); finishing at tick %d", path, exc, out.ticks)
                break
            out.write(batch)
    finally:
        out.finish()
