"""The top view of a Fig. 8 task's seeded trials (chair, trash): where each object started and ended, its goal
and the tolerance, succeeded trials in green, failed in red."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_top_view(path: Path, title: str, starts_m, ends_m, ok, goals_m=None, goal_tol_m: float = 0.0,
                  box_m: tuple[float, float, float, float] | None = None) -> None:
    """`starts_m`, `ends_m` (N, 2) world x-y [m]; `ok` (N,) bool; `goals_m` (N, 2) drawn as circles of
    `goal_tol_m`; `box_m` (x_min, y_min, x_max, y_max) an outline (the trash box's hole)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    starts, ends, ok = np.asarray(starts_m, float), np.asarray(ends_m, float), np.asarray(ok, bool)
    fig, ax = plt.subplots(figsize=(6, 5))
    for k in range(len(starts)):
        colour = "tab:green" if ok[k] else "tab:red"
        ax.annotate("", ends[k], starts[k], arrowprops={"arrowstyle": "->", "color": colour, "lw": 1})
        ax.plot(*starts[k], "o", color=colour, ms=4)
        ax.text(starts[k][0], starts[k][1], f" {k}", fontsize=7)
        if goals_m is not None:
            ax.add_patch(plt.Circle(tuple(np.asarray(goals_m, float)[k]), goal_tol_m, fill=False, color="grey",
                                    lw=0.8))
    if box_m is not None:
        x0, y0, x1, y1 = box_m
        ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="black", lw=1, label="hole")
        ax.legend(fontsize=8, loc="best")
    ax.plot(0.0, 0.0, "k^", ms=8)
    ax.text(0.0, 0.0, "  robot start", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (world)")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
