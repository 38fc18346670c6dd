"""The robot side of a session recording: inputs and ticks are appended to a batch in the loop's thread (a copy
of the log row the DataLogger just filled and of the simulator's qpos; verbs as tagged JSON, setpoints as plain
tuples), and every BATCH_TICKS ticks the batch is written to a non-blocking pipe in one system call (the two
arrays' own memory and the events pickled), read by the session writer, a process of its own
(app.session.writer) that makes the JSON, the MCAP and the file. No encoding of telemetry, no file I/O and no
helper thread in this process: a thread here would take the interpreter lock from the loop whenever it ran.
When the pipe is full the bytes wait here and go with the next batch; the loop never waits for the writer.

What a crash loses: the recording process killed, at most the last BATCH_TICKS ticks (0.1 s at 5 ms) and the
inputs since them (the writer finishes the file with what it got); the writer killed too, also what it had
received and not flushed (it flushes after each batch)."""

from __future__ import annotations

import collections
import datetime
import fcntl
import itertools
import logging
import math
import multiprocessing
import os
import select
import threading
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from app.service.log_row import COLUMNS, ROW_LENGTH
from app.session.inputs import SETPOINT_COLUMNS, setpoint_row

log = logging.getLogger(__name__)

BATCH_TICKS = 20  # ticks per batch: 0.1 s at 5 ms, the most a crash of the recording process loses
MAX_PENDING_BYTES = 64 << 20  # bytes waiting for the writer before the recording gives up on it (~25 s of ticks)
PIPE_BYTES = 1 << 20  # asked of the OS for the pipe (Linux F_SETPIPE_SZ; its default is 64 kB): ~25 batches
FORMAT = 1  # the session file's format version (header "format")
_F_SETPIPE_SZ = 1031
IOV_MAX = 64  # buffers per writev (the system allows 1024)


class SessionRecorder:
    """Records one session to `path` (an MCAP file, written by a writer process started here).

    The host calls `input(...)` for each input it applied at a tick boundary and `tick(row, qpos)` after each
    tick; `close()` ends the recording and waits for the file to be finished."""

    def __init__(self, path: str | Path, header: Mapping[str, Any]) -> None:
        from app.session.writer import BatchFrame, writer_main

        self.path = Path(path)
        self.header = {"format": FORMAT, "columns": list(COLUMNS), "batch_ticks": BATCH_TICKS,
                       "recorded_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
                       **_plain(header)}
        self.dt_s = float(self.header["dt_control_s"])
        self.ticks = 0  # ticks recorded so far: the tick index of the next input
        self.inputs = 0
        self.unreplayable = 0
        self.error: str | None = None
        self.closed = False
        self._finished = threading.Event()
        self._frame_cls = BatchFrame
        ctx = multiprocessing.get_context("spawn")
        # the writer holds only the reading end: when this process dies, even in the middle of a batch, the writer
        # reads the end of the pipe and finishes the file
        reading, writing = ctx.Pipe(duplex=False)
        self._writing = writing
        self._fd = writing.fileno()
        try:
            fcntl.fcntl(self._fd, _F_SETPIPE_SZ, PIPE_BYTES)
        except OSError:  # not Linux, or above the system's limit: the default size, more waits here
            pass
        os.set_blocking(self._fd, False)
        self._pending: collections.deque[memoryview] = collections.deque()  # bytes the pipe had no room for
        self._pending_bytes = 0
        self._process = ctx.Process(target=writer_main, args=(str(self.path), self.header, reading),
                                    name="hrp2-session-writer", daemon=True)
        # the writer's start (fork and exec: milliseconds) is not the loop's to wait for; batches wait in the pipe
        self._starter = threading.Thread(target=self._start_writer, args=(reading,), name="session-writer-start",
                                         daemon=True)
        self._starter.start()
        self._nq = 0
        self._order = 0  # numbers the events, setpoints included: the writer puts them back in this order
        self._new_batch()

    def __repr__(self) -> str:
        return f"SessionRecorder({str(self.path)!r}, ticks={self.ticks}, error={self.error!r})"

    def _start_writer(self, reading) -> None:
        try:
            self._process.start()
        except Exception as exc:  # noqa: BLE001 - said in the status; the loop goes on without recording
            self._fail(f"the session writer could not start: {type(exc).__name__}: {exc}")
        finally:
            reading.close()  # the writer's end

    def _new_batch(self) -> None:
        self._first = self.ticks
        self._events: list[tuple] = []  # (order, tick, topic, message)
        self._k = 0  # setpoint rows used
        self._n = 0
        if self._pending or not hasattr(self, "_rows"):  # the pipe still holds views of the arrays: new ones
            self._rows = np.empty((BATCH_TICKS, ROW_LENGTH))
            self._qpos = np.empty((BATCH_TICKS, self._nq))
            self._setpoints = np.empty((4 * BATCH_TICKS, len(SETPOINT_COLUMNS)))  # grows when a batch needs more

    # ---- the hot path --------------------------------------------------------------------------------------
    def tick(self, row: np.ndarray, qpos: np.ndarray) -> None:
        """After each tick: its log row and the simulator's qpos (both copied)."""
        n = self._n
        if len(qpos) != self._nq:  # the first tick, or a reset to a scene of another size
            if n:
                self._send()
                n = 0
            self._nq = len(qpos)
            self._qpos = np.empty((BATCH_TICKS, self._nq))  # (the inputs before this tick stay in the batch)
        self._rows[n] = row
        self._qpos[n] = qpos
        self.ticks += 1
        self._n = n = n + 1
        if n == BATCH_TICKS:
            self._send()

    def _send(self) -> None:
        if self.error is None:
            parts = self._frame_cls.parts(self._first, self._rows[:self._n], self._qpos[:self._n], self._events,
                                          self._setpoints[:self._k])
            self._pending.extend(parts)
            self._pending_bytes += sum(len(p) for p in parts)
            self._write_pending()
        self._new_batch()

    def _write_pending(self) -> None:
        pending = self._pending
        try:
            while pending:  # (no empty buffer is ever queued: each writev moves at least one byte)
                written = os.writev(self._fd, list(itertools.islice(pending, IOV_MAX)))
                self._pending_bytes -= written
                while pending and written >= len(pending[0]):
                    written -= len(pending.popleft())
                if written:
                    pending[0] = pending[0][written:]
        except BlockingIOError:  # the pipe is full: the rest goes with the next batch
            if self._pending_bytes > MAX_PENDING_BYTES:
                self._fail(f"the session writer fell {self._pending_bytes >> 20} MB behind")
        except OSError as exc:  # the writer is gone
            self._fail(f"the session writer is gone (exit code {self._process.exitcode}): {exc}")

    def _fail(self, why: str) -> None:
        """Give up on the writer (the loop never waits for it), saying why."""
        if self.error is None:
            self.error = f"{why}; recording stopped at tick {self.ticks}"
            log.error("%s: %s", self.path, self.error)

    # ---- inputs --------------------------------------------------------------------------------------------
    def event(self, topic: str, message: dict) -> None:
        """Something to write before the next recorded tick (an input, a parameter change, a run's change)."""
        self._order += 1
        self._events.append((self._order, self.ticks, topic, message))

    def input(self, kind: str, phase: str, name: str, time_s: float, value: Any, outcome: dict) -> None:
        """A verb or the e-stop applied at the boundary before the next tick (value: the verb, or None)."""
        from app.session.channels import INPUTS_TOPIC
        from app.session.inputs import Unencodable, encode

        try:
            encoded, replayable = encode(value), True
        except Unencodable as exc:
            encoded, replayable = {"$unencodable": str(exc)}, False
            self.unreplayable += 1
        self.inputs += 1
        self.event(INPUTS_TOPIC, {"tick": self.ticks, "time_s": float(time_s), "kind": kind, "phase": phase,
                                  "name": name, "input": encoded, "outcome": outcome, "replayable": replayable})

    def setpoints(self, phase: str, time_s: float, setpoints, acks) -> None:
        """Streamed setpoints applied before the next tick ("hook": taken at its start; "boundary": handed
        over between ticks), packed as numbers: the writer makes their JSON (app.session.inputs)."""
        self.inputs += 1
        self._order += 1
        k = self._k
        if k + len(acks) > len(self._setpoints):
            self._setpoints = np.concatenate([self._setpoints, np.empty_like(self._setpoints)])
        table = self._setpoints
        for sp, ack in zip(setpoints, acks, strict=True):
            table[k] = setpoint_row(self._order, self.ticks, phase, time_s, sp, ack.ignored)
            k += 1
        self._k = k

    def params_changed(self, time_s: float, changes: Mapping[str, Any]) -> None:
        from app.session.channels import PARAMS_TOPIC

        self.event(PARAMS_TOPIC, {"tick": self.ticks, "time_s": float(time_s), "changes": _plain(changes)})

    def runs_changed(self, time_s: float, runs) -> None:
        from app.session.channels import BEHAVIORS_TOPIC

        self.event(BEHAVIORS_TOPIC, {"tick": self.ticks, "time_s": float(time_s),
                                     "runs": [_plain(r.to_dict()) for r in runs]})

    # ---- the end -------------------------------------------------------------------------------------------
    @property
    def writer_pid(self) -> int | None:
        """The writer process's id once it has started."""
        return self._process.pid

    def status(self) -> dict[str, Any]:
        """closed: no more ticks are taken; finished: the writer has finished the file (or given up: error)."""
        return {"path": str(self.path), "name": self.path.name, "ticks": self.ticks,
                "duration_s": round(self.ticks * self.dt_s, 6), "inputs": self.inputs,
                "unreplayable_inputs": self.unreplayable, "error": self.error, "closed": self.closed,
                "finished": self._finished.is_set()}

    def close_async(self, timeout_s: float = 30.0) -> None:
        """Take no more ticks, send what is left, and let a thread wait for the writer to finish the file (the
        loop does not wait: `finished` in the status, or `wait`)."""
        if self.closed:
            return
        if self._n or self._events or self._k:
            self._send()
        self.closed = True
        threading.Thread(target=self._finish, args=(timeout_s,), name="session-writer-finish", daemon=True).start()

    def wait(self, timeout_s: float = 30.0) -> dict[str, Any]:
        """Wait until the file is finished; the recording's status."""
        if not self._finished.wait(timeout_s):
            self._fail(f"the session writer did not finish within {timeout_s:g} s")
        return self.status()

    def close(self, timeout_s: float = 30.0) -> dict[str, Any]:
        """close_async, then wait: the status once the file is finished."""
        self.close_async(timeout_s)
        return self.wait(timeout_s + 5.0)

    def _finish(self, timeout_s: float) -> None:
        try:
            deadline = time.monotonic() + timeout_s
            self._starter.join(timeout_s)
            while self.error is None and self._pending:  # the rest, as the writer takes it
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    self._fail(f"the session writer did not take the last {self._pending_bytes >> 10} kB within "
                               f"{timeout_s:g} s")
                    break
                select.select((), (self._fd,), (), min(remaining, 0.5))
                self._write_pending()
            self._writing.close()  # the end of the pipe: the writer finishes the file
            if self._process.pid is None:
                self._fail("the session writer could not start")
                return
            self._process.join(max(1.0, deadline - time.monotonic()))
            if self._process.is_alive():
                self._fail(f"the session writer did not finish within {timeout_s:g} s")
                self._process.terminate()
            elif self._process.exitcode != 0:
                self._fail(f"the session writer exited with code {self._process.exitcode}")
        finally:
            self._finished.set()


def _plain(value: Any) -> Any:
    """A JSON-able copy (tuples as lists; anything else as its text; non-finite floats as null)."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, (np.floating, np.integer)):
        return _plain(value.item())
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return str(value)
