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
    row[i] = float(snap.emergency.get("hard_stop", False))
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

    def __init__(self, max_length: int = 12000) -> None:
        self._rows = np.zeros((max_length, ROW_LENGTH))
        self._next = 0  # ring index of the next row
        self._count = 0  # rows held
        self._lock = threading.Lock()

    def record(self, snap) -> None:
        """Store snapshot_row(snap)."""
        with self._lock:
            _fill_row(self._rows[self._next], snap)
            self._next = (self._next + 1) % len(self._rows)
            self._count = min(self._count + 1, len(self._rows))

    def clear(self) -> None:
        with self._lock:
            self._next = self._count = 0

    def __len__(self) -> int:
        return self._count

    def rows(self) -> np.ndarray:
        """The rows held, oldest first, (n, ROW_LENGTH) (a copy)."""
        with self._lock:
            if self._count < len(self._rows):
                return self._rows[:self._count].copy()
            return np.concatenate((self._rows[self._next:], self._rows[:self._next]))

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
