"""The session writer: a process of its own that turns the recorder's batches (rows, the simulator's qpos, the
inputs and events of some ticks) into MCAP messages and flushes the file after each batch. It finishes the file
(summary, footer) on the recorder's end marker, or when the process that records has died.

It imports no simulation and no controller: numpy, mcap and the channel definitions only."""

from __future__ import annotations

import hashlib
import logging
import os
import pickle
import signal
import struct
from collections.abc import Mapping
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

from app.session.channels import DIGEST_TOPIC, INPUTS_TOPIC, SESSION_METADATA
from app.session.inputs import SETPOINT_COLUMNS, setpoint_inputs
from app.session.mcap_log import McapLog, time_ns

log = logging.getLogger(__name__)


@dataclass
class Batch:
    """The recorder's ticks [first_tick, first_tick + len(rows)) and the events up to the next tick boundary.

    `events`: (order, tick, topic, message); `setpoints`: rows of app.session.inputs.SETPOINT_COLUMNS (their
    messages are made here); `order` numbers both in the order they happened. An input at tick k took effect
    before the k-th recorded tick (at the boundary after tick k - 1)."""

    first_tick: int
    rows: np.ndarray  # (n, ROW_LENGTH)
    qpos: np.ndarray  # (n, nq): the simulator's configuration after each tick
    events: list[tuple] = field(default_factory=list)
    setpoints: np.ndarray | None = None  # (k, len(SETPOINT_COLUMNS))

    def messages(self) -> list[tuple[int, str, dict]]:
        """Every event as (tick, topic, message), in the order they happened."""
        merged = [(order, tick, topic, message) for order, tick, topic, message in self.events]
        if self.setpoints is not None and len(self.setpoints):
            merged += [(order, tick, INPUTS_TOPIC, message) for order, tick, message in setpoint_inputs(self.setpoints)]
        merged.sort(key=lambda e: e[0])
        return [(tick, topic, message) for _, tick, topic, message in merged]


class BatchFrame:
    """A Batch on the pipe, framed as multiprocessing.connection frames a message (a 4-byte big-endian length),
    so the writer reads it with Connection.recv_bytes: a header (first tick, ticks, row width, nq, bytes of the
    pickled events), the rows' and qpos' float64 bytes as they lie in memory, the events pickled."""

    HEADER = struct.Struct("<qiiiii")

    @classmethod
    def parts(cls, first_tick: int, rows: np.ndarray, qpos: np.ndarray, events: list,
              setpoints: np.ndarray) -> list[memoryview]:
        """The frame as buffers for one writev: nothing copied but the (rare) events' pickle."""
        pickled = pickle.dumps(events, protocol=pickle.HIGHEST_PROTOCOL) if events else b""
        n, width = rows.shape
        nq = qpos.shape[1]
        body = [_raw(rows), _raw(qpos), _raw(setpoints)]
        size = cls.HEADER.size + sum(b.nbytes for b in body) + len(pickled)
        head = struct.pack("!i", size) + cls.HEADER.pack(first_tick, n, width, nq, len(setpoints), len(pickled))
        return [b for b in (memoryview(head), *body, memoryview(pickled)) if b.nbytes]

    @classmethod
    def read(cls, data: bytes) -> Batch:
        first, n, width, nq, k, events_len = cls.HEADER.unpack_from(data)
        at = cls.HEADER.size
        rows = np.frombuffer(data, np.float64, n * width, at).reshape(n, width)
        at += rows.nbytes
        qpos = np.frombuffer(data, np.float64, n * nq, at).reshape(n, nq)
        at += qpos.nbytes
        setpoints = np.frombuffer(data, np.float64, k * len(SETPOINT_COLUMNS), at).reshape(k, len(SETPOINT_COLUMNS))
        at += setpoints.nbytes
        events = pickle.loads(data[at:at + events_len]) if events_len else []
        return Batch(first, rows, qpos, events, setpoints)


def _raw(a: np.ndarray) -> memoryview:
    """The bytes of a C-contiguous float64 array, not copied (empty: an empty view)."""
    return memoryview(a).cast("B") if a.size else memoryview(b"")


def qpos_digest(qpos: np.ndarray) -> str:
    """8 bytes of BLAKE2b over the float64 bytes of qpos, as hex."""
    return hashlib.blake2b(np.ascontiguousarray(qpos, dtype=np.float64).tobytes(), digest_size=8).hexdigest()


class SessionFile:
    """An open session file: the header as metadata, then batches."""

    def __init__(self, path: str, header: Mapping[str, Any]) -> None:
        self.dt_s = float(header["dt_control_s"])
        self.log = McapLog(path, SESSION_METADATA, header, session=True)
        self.ticks = 0

    def _event(self, tick: int, topic: str, message) -> None:
        self.log.write(topic, time_ns(tick * self.dt_s), message)

    def write(self, batch: Batch) -> None:
        log_ = self.log
        events = iter(batch.messages())
        pending = next(events, None)
        for i, row in enumerate(batch.rows):
            tick = batch.first_tick + i
            while pending is not None and pending[0] <= tick:
                self._event(*pending)
                pending = next(events, None)
            t_ns = time_ns((tick + 1) * self.dt_s)  # the state after the tick
            log_.write_row(tick, t_ns, row)
            q = batch.qpos[i]
            log_.write(DIGEST_TOPIC, t_ns, {"tick": tick, "time_s": float(row[0]), "qpos_blake2b": qpos_digest(q),
                                            "nq": int(len(q))})
            self.ticks = tick + 1
        while pending is not None:
            self._event(*pending)
            pending = next(events, None)
        log_.flush()

    def finish(self) -> None:
        self.log.finish()


def yield_to_the_loop() -> str:
    """SCHED_BATCH for this process: a batch that arrives does not preempt the task running on that core
    (measured: a writer woken by each batch took the loop's core for up to 8-17 ms on a loaded 2-core machine);
    its share of the CPU stays (a nice value of 10 more starved it for minutes on a machine loaded 9 deep). What
    was set, as text."""
    try:
        os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))
        return "SCHED_BATCH"
    except (AttributeError, OSError):
        return "default"


def writer_main(path: str, header: Mapping[str, Any], batches: Connection) -> None:
    """The process's main: write batches until the pipe ends (the recorder closed it, or its process died: this
    process holds only the reading end, so either way the end of the pipe is read)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the recorder decides
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s session-writer %(name)s: %(message)s")
    yield_to_the_loop()
    out = SessionFile(path, header)
    try:
        while True:
            try:
                batch = BatchFrame.read(batches.recv_bytes())
            except EOFError:
                break
            except Exception as exc:  # noqa: BLE001 - a batch cut short by the recorder's death
                log.error("%s: the last batch could not be read (%s); finishing at tick %d", path, exc, out.ticks)
                break
            out.write(batch)
    finally:
        out.finish()
