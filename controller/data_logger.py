"""DataLogger: a ring buffer of snapshots, exported as CSV (PlotJuggler and Foxglove open it)."""

from __future__ import annotations

import csv
import io
import threading
from collections import deque
from pathlib import Path

import numpy as np

from robot.names import FORCE_SENSOR_NAMES, JOINT_NAMES


def snapshot_row(snap) -> list[float]:
    """One CSV row: time, commanded and measured joints [rad], attitude, COG, ZMP, wrenches, flags."""
    return [
        snap.time_s,
        *snap.q_cmd_rad, *snap.q_meas_rad,
        *snap.base_rpy_est_rad, *snap.cog_world, *snap.zmp_world,
        *np.asarray(snap.wrenches_ext).ravel(),
        float(snap.emergency.get("hard_stop", False)),
        *snap.truth.base_pos_world, float(snap.fallen),
    ]


def csv_header() -> list[str]:
    h = ["time_s"]
    h += [f"q_cmd/{n}" for n in JOINT_NAMES] + [f"q_meas/{n}" for n in JOINT_NAMES]
    h += [f"rpy_est/{a}" for a in ("roll", "pitch", "yaw")]
    h += [f"cog/{a}" for a in "xyz"] + [f"zmp/{a}" for a in "xyz"]
    h += [f"wrench/{s}/{c}" for s in FORCE_SENSOR_NAMES for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
    h += ["emergency/hard_stop", "truth/base_x", "truth/base_y", "truth/base_z", "truth/fallen"]
    return h


class DataLogger:
    """Keeps the last `max_length` snapshots (hrpsys DataLogger's ring buffer); thread-safe.

    `record` only appends a reference to the immutable snapshot: no I/O on the hot path.
    """

    def __init__(self, max_length: int = 12000) -> None:
        self._buf: deque = deque(maxlen=max_length)
        self._lock = threading.Lock()

    def record(self, snap) -> None:
        with self._lock:
            self._buf.append(snap)

    def clear(self) -> None:
        with self._lock:
            self._buf.clear()

    def __len__(self) -> int:
        return len(self._buf)

    def snapshots(self) -> list:
        with self._lock:
            return list(self._buf)

    def to_csv(self, path: str | Path | None = None) -> str:
        """Write the buffer as CSV to `path` (if given) and return the text."""
        out = io.StringIO()
        w = csv.writer(out, lineterminator="\n")
        w.writerow(csv_header())
        for snap in self.snapshots():
            w.writerow([f"{v:.6g}" for v in snapshot_row(snap)])
        text = out.getvalue()
        if path is not None:
            Path(path).write_text(text)
        return text
