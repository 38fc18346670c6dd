"""The capture-point error plot: its samples (a ring buffer of the Stabilizer's status over the last seconds,
with the support edge) and the uPlot that draws them, with the line of current values under it."""

from __future__ import annotations

import math
import threading
from collections import deque

import numpy as np

from app.service.state_document import support_edge_mm

PLOT_WINDOW_S = 10.0  # [s] of simulated time shown by the capture-point error plot
PLOT_RATE_HZ = 25.0  # plot samples and redraws per second (wall time): the issue asks >= 20
PLOT_RANGE_MM = 100.0  # the plot's fixed y range +-[mm]: the default 40 mm threshold stays readable


class CpErrorHistory:
    """Ring buffer of (sim time [s], CP error x, y [mm], threshold [mm], flag, support edge [mm]) over the last
    `window_s`."""

    def __init__(self, window_s: float = PLOT_WINDOW_S, maxlen: int = 2000) -> None:
        self.window_s = float(window_s)
        self._rows: deque[tuple[float, ...]] = deque(maxlen=maxlen)
        self._lock = threading.Lock()  # the viewer's thread and a caller may add the same snapshot at once

    def __len__(self) -> int:
        return len(self._rows)

    def add(self, snap) -> bool:
        """Sample the snapshot's Stabilizer status; False when it has none. A reset clears the buffer."""
        st = snap.layers.get("st")
        if st is None:
            return False
        t = float(snap.time_s)
        ex, ey = st.cp_error
        edge = support_edge_mm(snap)
        with self._lock:
            rows = self._rows
            if rows and t < rows[-1][0]:
                rows.clear()  # the simulation was reset
            if rows and t == rows[-1][0]:
                return False
            if edge is None:  # no gait reference: the last known edge, else the plot's range
                edge = rows[-1][5] if rows else PLOT_RANGE_MM
            rows.append((t, 1e3 * float(ex), 1e3 * float(ey), 1e3 * float(st.cp_threshold_m),
                         1.0 if st.emergency else 0.0, min(float(edge), PLOT_RANGE_MM)))
            while rows and rows[0][0] < t - self.window_s:
                rows.popleft()
        return True

    def latest(self) -> tuple[float, float, float, float, bool] | None:
        """The newest row: (time [s], err x, err y, threshold [mm], flag), or None."""
        if not self._rows:
            return None
        t, ex, ey, thr, flag, _ = self._rows[-1]
        return t, ex, ey, thr, bool(flag)

    def data(self) -> tuple[np.ndarray, ...]:
        """(time, err x, err y, +threshold, -threshold, +support edge, -support edge, flag band) arrays for the
        uPlot; the flag band is at the top of the fixed range while the CP flag is raised and at its bottom
        otherwise (filled down: shaded)."""
        with self._lock:
            if not self._rows:
                z = np.zeros(1)
                return z, z, z, z, z, z, z, np.full(1, -PLOT_RANGE_MM)
            a = np.asarray(self._rows, dtype=float)
        band = np.where(a[:, 4] > 0.5, PLOT_RANGE_MM, -PLOT_RANGE_MM)
        return (a[:, 0].copy(), a[:, 1].copy(), a[:, 2].copy(), a[:, 3].copy(), -a[:, 3], a[:, 5].copy(), -a[:, 5],
                band)


def add_cp_plot(gui, history: CpErrorHistory):
    """The uPlot of `history` in a viser GUI (its handle: set `.data` to `history.data()` to redraw)."""
    return gui.add_uplot(
        history.data(),
        ({"label": "t [s]"},
         {"label": "CP err x [mm]", "stroke": "#e6194b", "width": 1.5},
         {"label": "CP err y [mm]", "stroke": "#3c78d8", "width": 1.5},
         {"label": "+threshold", "stroke": "#888888", "width": 1, "dash": (6.0, 4.0)},
         {"label": "-threshold", "stroke": "#888888", "width": 1, "dash": (6.0, 4.0)},
         {"label": "+support edge", "stroke": "#b8860b", "width": 1, "dash": (2.0, 3.0)},
         {"label": "-support edge", "stroke": "#b8860b", "width": 1, "dash": (2.0, 3.0)},
         {"label": "CP flag", "stroke": "rgba(200,16,46,0)", "width": 0, "fill": "rgba(200,16,46,0.18)",
          "fillTo": -PLOT_RANGE_MM,
          "points": {"show": False}}),
        title="capture-point error [mm] (dashed grey: threshold; dotted: support edge; shaded: CP flag raised)",
        scales={"x": {"time": False}, "y": {"auto": False, "range": (-PLOT_RANGE_MM, PLOT_RANGE_MM)}},
        legend={"show": True, "live": True},
        aspect=1.6,
    )


def cp_legend(history: CpErrorHistory) -> str:
    """The plot's current values, as a line under it (uPlot's own legend shows them under the cursor)."""
    row = history.latest()
    if row is None:
        return "CP error: no Stabilizer"
    t, ex, ey, thr, flag = row
    return (f"t {t:.2f} s: x **{ex:+.1f}** mm, y **{ey:+.1f}** mm, |e| {math.hypot(ex, ey):.1f} / threshold "
            f"{thr:.1f} mm, flag **{'RAISED' if flag else 'off'}**")
