"""DataLogger: a ring buffer of the ticks' log rows (app.service.log_row), exported as MCAP (Foxglove and
PlotJuggler open it: JSON channels with their schemas) or CSV."""

from __future__ import annotations

import csv
import io
import threading
from pathlib import Path

import numpy as np

from app.service.log_row import COLUMNS, ROW_LENGTH, RowFiller

__all__ = ["ROW_LENGTH", "DataLogger", "csv_header"]


def csv_header() -> list[str]:
    """The CSV columns: the log row's (time_s, then topic/field/component, e.g. joints/q_cmd_rad/RLEG_JOINT0)."""
    return list(COLUMNS)


class DataLogger:
    """Keeps the log rows of the last `max_length` ticks (hrpsys DataLogger's ring buffer); thread-safe.

    `record` copies the row's numbers into a preallocated array: no I/O on the hot path, and no snapshot
    kept alive (thousands of retained snapshots would be thousands of objects for the garbage collector
    to walk through, in pauses of milliseconds).
    """

    def __init__(self, max_length: int = 12000, storage: np.ndarray | None = None) -> None:
        """`storage` (max_length + 1, ROW_LENGTH) float64, e.g. in shared memory, lets another process read
        the log while this one writes it (`DataLogger.reader(storage)`); row 0 holds the write counter."""
        if storage is None:
            storage = np.zeros((max_length + 1, ROW_LENGTH))
        if storage.shape != (max_length + 1, ROW_LENGTH) or storage.dtype != np.float64:
            raise ValueError(f"storage must be float64 of shape ({max_length + 1}, {ROW_LENGTH})")
        self._storage = storage
        self._rows = storage[1:]
        self._written = storage[0]  # [0]: rows written since the last clear (a float holds 2^53 exactly)
        self._lock = threading.Lock()
        self._filler = RowFiller()

    @staticmethod
    def storage_shape(max_length: int) -> tuple[int, int]:
        return (max_length + 1, ROW_LENGTH)

    @classmethod
    def reader(cls, storage: np.ndarray) -> DataLogger:
        """A view of a log another process writes into `storage`."""
        return cls(storage.shape[0] - 1, storage)

    def record(self, obs) -> np.ndarray:
        """Store the row of one Observation (a snapshot with the simulator's truth beside it); returns the
        ring's row it was written to (valid until max_length more rows are recorded)."""
        with self._lock:
            n = int(self._written[0])
            row = self._rows[n % len(self._rows)]
            self._filler.fill(row, obs)
            self._written[0] = n + 1
        return row

    @property
    def written(self) -> int:
        """Rows recorded since the last clear."""
        return int(self._written[0])

    def last_row(self) -> np.ndarray:
        """A copy of the newest row (NaN before the first)."""
        with self._lock:
            n = int(self._written[0])
            if n == 0:
                return np.full(ROW_LENGTH, np.nan)
            return self._rows[(n - 1) % len(self._rows)].copy()

    def clear(self) -> None:
        with self._lock:
            self._written[0] = 0

    def __len__(self) -> int:
        return min(int(self._written[0]), len(self._rows))

    def rows(self) -> np.ndarray:
        """The rows held, oldest first, (n, ROW_LENGTH) (a copy). A row the writer overwrote while this
        copy was being taken is dropped."""
        size = len(self._rows)
        with self._lock:
            n0 = int(self._written[0])
            if n0 <= size:
                out = self._rows[:n0].copy()
            else:
                nxt = n0 % size
                out = np.concatenate((self._rows[nxt:], self._rows[:nxt]))
            n1 = int(self._written[0])
        # the writer puts row k into slot k % size: rows written meanwhile replaced the oldest ones copied
        overwritten = min(len(out), max(0, n1 - max(n0, size)))
        return out[overwritten:]

    def to_mcap(self, out) -> int:
        """Write the buffer as MCAP to `out` (a path or a binary stream); returns the number of rows. The row's
        channels (joints, base, balance, flags, wrenches, footsteps, operation targets) and BODY's transform,
        stamped with the control time; `tick` counts the rows recorded since the last reset."""
        from app.session.mcap_log import rows_to_mcap

        with self._lock:
            total = int(self._written[0])
        rows = self.rows()
        return rows_to_mcap(rows, out, range(total - len(rows), total), {"source": "DataLogger"})

    def to_csv(self, path: str | Path | None = None) -> str:
        """Write the buffer as CSV to `path` (if given) and return the text (an export: MCAP is the log)."""
        out = io.StringIO()
        w = csv.writer(out, lineterminator="\n")
        w.writerow(csv_header())
        for row in self.rows().tolist():
            w.writerow([f"{v:.6g}" for v in row])
        text = out.getvalue()
        if path is not None:
            Path(path).write_text(text)
        return text
