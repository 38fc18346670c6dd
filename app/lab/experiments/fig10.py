"""The Fig. 10-like plot of an experiment: CP error, threshold, support-polygon edge, motion stopped."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_fig10(data: np.ndarray, flag_time: float | None, title: str, path: Path) -> None:
    """`data` rows as the experiment CSV (time, error x, y, |error|, threshold, CP-to-edge, flag, stopped, fallen)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = data[:, 0]
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, data[:, 3] * 1e3, color="tab:red", label="capture-point error")
    ax.plot(t, data[:, 4] * 1e3, color="tab:blue", label="threshold")
    ax.plot(t, (data[:, 3] + data[:, 5]) * 1e3, color="black", ls="--", lw=1,
            label="error at which the CP leaves the support polygon")
    top = max(data[:, 3].max(), data[:, 4].max()) * 1e3 * 1.2
    top = min(top, 300.0)  # a fall sends the error to metres: keep the approach to the edge readable
    ax.fill_between(t, 0, data[:, 7] * top, color="tab:pink", alpha=0.3, label="motion stopped")
    if flag_time is not None:
        ax.axvline(flag_time, color="tab:pink", lw=1)
    fell = np.flatnonzero(data[:, 8] > 0.5)
    if fell.size:
        ax.axvline(t[fell[0]], color="black", lw=1.5, label="fallen")
    ax.set_ylim(0, max(top, 1.0))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("[mm]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
