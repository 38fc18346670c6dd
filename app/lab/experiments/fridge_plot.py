"""The fridge trial's plot: the door's angle, and the two hands' twists from the operation layer's status (the
behaviour's at the right hand, the stick's at the left), whose overlap is Eq. 5 for two points."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_fridge(series, path: Path) -> Path:
    """series: (time [s], door [deg], |rhand behaviour twist| [m/s], |lhand stick twist| [m/s]) per tick."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = np.asarray(series, dtype=float)
    if data.ndim != 2 or data.shape[1] != 4 or len(data) < 2:
        raise ValueError(f"series must be (N >= 2, 4) rows, got shape {data.shape}")
    t = data[:, 0]
    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    ax0.plot(t, data[:, 1], color="tab:blue")
    ax0.set_ylabel("door [deg]")
    ax0.grid(alpha=0.3)
    ax1.plot(t, 1e3 * data[:, 2], label="rhand: open_door's twist", color="tab:red")
    ax1.plot(t, 1e3 * data[:, 3], label="lhand: operator's stick", color="tab:green")
    both = (data[:, 2] > 0) & (data[:, 3] > 0)
    ax1.fill_between(t, 0, 1e3 * np.maximum(data[:, 2], data[:, 3]).max(), where=both, color="0.85",
                     label="both in the same tick (Eq. 5)")
    ax1.set_ylabel("|linear twist| [mm/s]")
    ax1.set_xlabel("time [s]")
    ax1.legend(loc="upper left", fontsize=8)
    ax1.grid(alpha=0.3)
    fig.suptitle("fridge: the right hand opens the door while the stick moves the left hand")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
