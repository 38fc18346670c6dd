"""The robot side of a session recording: inputs and ticks are appended to a batch in the loop's thread (a copy
of the log row the DataLogger just filled, a reference to the simulator's qpos, the inputs as tagged JSON), and
every BATCH_TICKS ticks the batch goes to the session writer, a process of its own (app.session.writer), through
a pipe a sender thread writes (the pickling is that thread's). No I/O and no encoding of telemetry on the hot path.

What a crash loses: the recording process killed, at most the last BATCH_TICKS ticks (0.1 s at 5 ms) and the
inputs since them (the writer finishes the file with what it got); the writer killed too, also what it had
received and not flushed (it flushes after each batch)."""

from __future__ import annotations

import datetime
import logging
import math
import multiprocessing
import queue
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from app.service.log_row import COLUMNS, ROW_LENGTH

log = logging.getLogger(__name__)

BATCH_TICKS = 20  # ticks per batch: 0.1 s at 5 ms, the most a crash of the recording process loses
MAX_BACKLOG = 200  # batches (20 s of ticks) queued for the writer before the recording gives up on it
FORMAT = 1  # the session file's format version (header "format")


class SessionRecorder:
    """Records one session to `path` (an MCAP file, written by a writer process started here).

    The host calls `input(...)` for each input it applied at a tick boundary and `tick(row, qpos)` after each
    tick; `close()` ends the recording and waits for the file to be finished."""

    def __init__(self, path: str | Path, header: Mapping[str, Any]) -> None:
        from app.session.writer import Batch, writer_main

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
        self._batch_cls = Batch
        ctx = multiprocessing.get_context("spawn")
        # the writer holds only the reading end: when this process dies, even in the middle of a batch, it reads
        # the end of the pipe (a multiprocessing.Queue would give it both ends, and it would wait for ever)
        reading, self._pipe = ctx.Pipe(duplex=False)
        self._process = ctx.Process(target=writer_main, args=(str(self.path), self.header, reading),
                                    name="hrp2-session-writer", daemon=True)
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        # the writer's start (a fork and exec, some milliseconds) and the sending are not the loop's to wait for
        self._sender = threading.Thread(target=self._send_all, args=(reading,), name="session-writer-send",
                                        daemon=True)
        self._sender.start()
        self._new_batch()

    def __repr__(self) -> str:
        return f"SessionRecorder({str(self.path)!r}, ticks={self.ticks}, error={self.error!r})"

    def _new_batch(self) -> None:
        self._first = self.ticks
        self._rows = np.empty((BATCH_TICKS, ROW_LENGTH))
        self._qpos: list[np.ndarray] = []
        self._events: list[tuple[int, str, dict]] = []
        self._n = 0

    # ---- the hot path --------------------------------------------------------------------------------------
    def tick(self, row: np.ndarray, qpos: np.ndarray) -> None:
        """After each tick: its log row (copied) and the simulator's qpos (immutable: kept, not copied)."""
        n = self._n
        self._rows[n] = row
        self._qpos.append(qpos)
        self.ticks += 1
        self._n = n = n + 1
        if n == BATCH_TICKS:
            self._send()

    def event(self, topic: str, message: dict) -> None:
        """Something to write before the next recorded tick (an input, a parameter change, a run's change)."""
        self._events.append((self.ticks, topic, message))

    def _send(self) -> None:
        if self.error is None:
            n = self._n
            self._queue.put(self._batch_cls(self._first, self._rows[:n], self._qpos, self._events))
            if self._queue.qsize() > MAX_BACKLOG:
                self._fail(f"the session writer fell {MAX_BACKLOG} batches behind")
        self._new_batch()

    def _fail(self, why: str) -> None:
        """Give up on the writer (the loop never waits for it), saying why."""
        if self.error is None:
            self.error = f"{why}; recording stopped at tick {self.ticks}"
            log.error("%s: %s", self.path, self.error)

    def _send_all(self, reading) -> None:
        """The sender thread: start the writer, then hand it each batch (None: the end)."""
        try:
            self._process.start()
        except Exception as exc:  # noqa: BLE001 - said in the status; the loop goes on without recording
            self._fail(f"the session writer could not start: {type(exc).__name__}: {exc}")
            return
        finally:
            reading.close()  # the writer's end only
        while True:
            batch = self._queue.get()
            try:
                if batch is None:
                    self._pipe.close()
                    return
                self._pipe.send(batch)
            except (OSError, ValueError) as exc:
                self._fail(f"the session writer is gone (exit code {self._process.exitcode}): {exc}")
                return

    # ---- inputs --------------------------------------------------------------------------------------------
    def input(self, kind: str, phase: str, name: str, time_s: float, value: Any, outcome: dict) -> None:
        """An input applied at the boundary before the next tick: a verb, the e-stop, or setpoints."""
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

    def params_changed(self, time_s: float, changes: Mapping[str, Any]) -> None:
        from app.session.channels import PARAMS_TOPIC

        self.event(PARAMS_TOPIC, {"tick": self.ticks, "time_s": float(time_s), "changes": _plain(changes)})

    def runs_changed(self, time_s: float, runs) -> None:
        from app.session.channels import BEHAVIORS_TOPIC

        self.event(BEHAVIORS_TOPIC, {"tick": self.ticks, "time_s": float(time_s),
                                     "runs": [_plain(r.to_dict()) for r in runs]})

    # ---- the end -------------------------------------------------------------------------------------------
    def status(self) -> dict[str, Any]:
        return {"path": str(self.path), "name": self.path.name, "ticks": self.ticks,
                "duration_s": round(self.ticks * self.dt_s, 6), "inputs": self.inputs,
                "unreplayable_inputs": self.unreplayable, "error": self.error, "closed": self.closed}

    def close(self, timeout_s: float = 30.0) -> dict[str, Any]:
        """Send what is left, end the writer, wait until the file is finished; the recording's status."""
        if self.closed:
            return self.status()
        if self._n or self._events:
            self._send()
        self.closed = True
        self._queue.put(None)
        self._sender.join(timeout_s)
        if self._process.pid is None:
            self._fail("the session writer could not start")
            return self.status()
        self._process.join(timeout_s)
        if self._process.is_alive():
            self._fail(f"the session writer did not finish within {timeout_s:g} s")
            self._process.terminate()
        elif self._process.exitcode != 0:
            self._fail(f"the session writer exited with code {self._process.exitcode}")
        return self.status()


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
