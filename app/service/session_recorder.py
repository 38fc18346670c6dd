"""The robot side of a session recording: inputs and ticks are appended to a batch in the loop's thread (a copy
of the log row the DataLogger just filled, a reference to the simulator's qpos, the inputs as tagged JSON), and
every BATCH_TICKS ticks the batch goes to the session writer, a process of its own (app.session.writer), through
a queue whose feeder thread does the pickling. No I/O and no encoding of telemetry on the hot path.

What a crash loses: the recording process killed, at most the last BATCH_TICKS ticks (0.1 s at 5 ms) and the
inputs since them (the writer finishes the file with what it got); the writer killed too, also what it had
received and not flushed (it flushes after each batch)."""

from __future__ import annotations

import datetime
import logging
import math
import multiprocessing
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
        self._queue = ctx.Queue()
        self._process = ctx.Process(target=writer_main, args=(str(self.path), self.header, self._queue),
                                    name="hrp2-session-writer", daemon=True)
        # the writer's start (a fork and exec, some milliseconds) is not the loop's to wait for: batches queue
        self._starter = threading.Thread(target=self._process.start, name="session-writer-start", daemon=True)
        self._starter.start()
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
            batch = self._batch_cls(self._first, self._rows[:n], self._qpos, self._events)
            self._queue.put(batch)
            self._check_writer()
        self._new_batch()

    def _check_writer(self) -> None:
        """Give up (and say why) when the writer died or falls far behind: the loop never waits for it."""
        proc = self._process
        if not self._starter.is_alive() and (proc.pid is None or proc.exitcode is not None):
            self.error = (f"the session writer could not start or exited (exit code {proc.exitcode}); recording "
                          f"stopped at tick {self.ticks}")
        elif self._queue.qsize() > MAX_BACKLOG:
            self.error = f"the session writer fell {MAX_BACKLOG} batches behind; recording stopped at tick {self.ticks}"
        if self.error is not None:
            log.error("%s", self.error)
            self._queue.cancel_join_thread()

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
        if self.error is None:
            self._queue.put(None)
        self._starter.join(timeout_s)
        if self._process.pid is None:
            self.error = self.error or "the session writer could not start"
            self._queue.cancel_join_thread()
            self._queue.close()
            return self.status()
        self._process.join(timeout_s)
        if self._process.is_alive():
            self.error = self.error or f"the session writer did not finish within {timeout_s:g} s"
            self._process.terminate()
            self._queue.cancel_join_thread()
        elif self._process.exitcode not in (0, None) and self.error is None:
            self.error = f"the session writer exited with code {self._process.exitcode}"
        self._queue.close()
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
