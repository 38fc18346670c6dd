"""DataLogger: a ring buffer of the snapshots' CSV rows (PlotJuggler and Foxglove open the CSV)."""

from __future__ import annotations

import csv
import io
import threading
from pathlib import Path

import numpy as np

from robot.names import FORCE_SENSOR_NAMES, JOINT_NAMES, NUM_JOINTS


def snapshot_row(snap) -> list[float]:
    """One CSV row: time, commanded and measured joints [rad], attitude, COG, ZMP, wrenches, flags."""
    return snapshot_row_array(snap).tolist()


def snapshot_row_array(snap) -> np.ndarray:
    """snapshot_row as a float array."""
    row = np.empty(ROW_LENGTH)
    _fill_row(row, snap)
    return row


def _fill_row(row: np.ndarray, snap) -> None:
    """Write snapshot_row(snap) into `row` (ROW_LENGTH,)."""
    n, k = NUM_JOINTS, 6 * len(FORCE_SENSOR_NAMES)
    row[0] = snap.time_s
    row[1:1 + n] = snap.q_cmd_rad
    row[1 + n:1 + 2 * n] = snap.q_meas_rad
    i = 1 + 2 * n
    row[i:i + 3] = snap.base_rpy_est_rad
    row[i + 3:i + 6] = snap.cog_world
    row[i + 6:i + 9] = snap.zmp_world
    row[i + 9:i + 9 + k] = np.asarray(snap.wrenches_ext).reshape(-1)
    i += 9 + k
    row[i] = float(snap.safety.hard_stop)
    row[i + 1:i + 4] = snap.truth.base_pos_world
    row[i + 4] = float(snap.fallen)


def csv_header() -> list[str]:
    h = ["time_s"]
    h += [f"q_cmd/{n}" for n in JOINT_NAMES] + [f"q_meas/{n}" for n in JOINT_NAMES]
    h += [f"rpy_est/{a}" for a in ("roll", "pitch", "yaw")]
    h += [f"cog/{a}" for a in "xyz"] + [f"zmp/{a}" for a in "xyz"]
    h += [f"wrench/{s}/{c}" for s in FORCE_SENSOR_NAMES for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
    h += ["emergency/hard_stop", "truth/base_x", "truth/base_y", "truth/base_z", "truth/fallen"]
    return h


#: the width of a CSV row (snapshot_row)
ROW_LENGTH = len(csv_header())


class DataLogger:
    """Keeps the CSV rows of the last `max_length` snapshots (hrpsys DataLogger's ring buffer); thread-safe.

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

    @staticmethod
    def storage_shape(max_length: int) -> tuple[int, int]:
        return (max_length + 1, ROW_LENGTH)

    @classmethod
    def reader(cls, storage: np.ndarray) -> DataLogger:
        """A view of a log another process writes into `storage`."""
        return cls(storage.shape[0] - 1, storage)

    def record(self, snap) -> None:
        """Store snapshot_row(snap)."""
        with self._lock:
            n = int(self._written[0])
            _fill_row(self._rows[n % len(self._rows)], snap)
            self._written[0] = n + 1

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

    def to_csv(self, path: str | Path | None = None) -> str:
        """Write the buffer as CSV to `path` (if given) and return the text."""
        out = io.StringIO()
        w = csv.writer(out, lineterminator="\n")
        w.writerow(csv_header())
        for row in self.rows().tolist():
            w.writerow([f"{v:.6g}" for v in row])
        text = out.getvalue()
        if path is not None:
            Path(path).write_text(text)
        return text
