"""Heatmaps of a study over threshold x T1, one column per T2: false alarms on the nominal tasks, stood with the
EmergencyStopper, falls rescued, CP margin at the flag, peak CP error, recovery time (a sampled study is binned)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from app.lab.study.analysis import ParamSummary

MAX_LEVELS = 6  # more distinct values than this (a random sample) are binned into BINS
BINS = 5

#: (title, value of a summary, colour map, "higher is better")
METRICS = (
    ("false alarms [nominal tasks]", lambda s: float(s.false_alarms), "Reds", False),
    ("stood with ES [%]", lambda s: None if s.stood_share is None else 100 * s.stood_share, "RdYlGn", True),
    ("falls w/o ES rescued [%]", lambda s: None if s.rescue_share is None else 100 * s.rescue_share, "RdYlGn", True),
    ("CP margin at flag [mm]", lambda s: s.margin_at_flag_mm, "viridis", True),
    ("peak CP error [mm]", lambda s: s.peak_error_mm, "magma_r", False),
    ("recovery after revert [s]", lambda s: s.recovery_s, "magma_r", False),
)


def levels(values: Sequence[float]) -> tuple[np.ndarray, list[str], int]:
    """(the level index of each value, the level labels, how many): the distinct values, or BINS equal bins."""
    v = np.asarray(values, dtype=float)
    distinct = np.unique(v)
    if len(distinct) <= MAX_LEVELS:
        return np.searchsorted(distinct, v), [f"{x:g}" for x in distinct], len(distinct)
    edges = np.linspace(distinct[0], distinct[-1], BINS + 1)
    index = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, BINS - 1)
    return index, [f"{a:.3g}-{b:.3g}" for a, b in zip(edges[:-1], edges[1:], strict=True)], BINS


def plot_heatmaps(summaries: Sequence[ParamSummary], path: Path, title: str,
                  recommended: ParamSummary | None = None) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    th_i, th_labels, n_th = levels([s.params.threshold_m * 1e3 for s in summaries])
    t1_i, t1_labels, n_t1 = levels([s.params.t1_s for s in summaries])
    t2_i, t2_labels, n_t2 = levels([s.params.t2_s for s in summaries])
    fig, axes = plt.subplots(len(METRICS), n_t2, figsize=(1.0 + 0.9 * n_t1 * n_t2 + 0.8 * n_t2, 2.3 * len(METRICS)),
                             squeeze=False, constrained_layout=True)
    for row, (name, value, cmap, _higher) in enumerate(METRICS):
        grids = np.full((n_t2, n_th, n_t1), np.nan)
        sums = np.zeros_like(grids)
        counts = np.zeros_like(grids)
        for k, s in enumerate(summaries):
            v = value(s)
            if v is not None:
                sums[t2_i[k], th_i[k], t1_i[k]] += v
                counts[t2_i[k], th_i[k], t1_i[k]] += 1
        with np.errstate(invalid="ignore"):
            grids = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
        finite = grids[np.isfinite(grids)]
        vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        if vmin == vmax:
            vmin, vmax = vmin - 1.0, vmax + 1.0
        for col in range(n_t2):
            ax = axes[row, col]
            im = ax.imshow(grids[col], origin="lower", cmap=cmap, vmin=vmin, vmax=vmax, aspect="auto")
            for (r, c), v in np.ndenumerate(grids[col]):
                if np.isfinite(v):
                    ax.text(c, r, f"{v:.0f}" if abs(v) >= 10 else f"{v:.2g}", ha="center", va="center", fontsize=7,
                            color="black", bbox={"boxstyle": "round,pad=0.1", "fc": "white", "alpha": 0.5, "lw": 0})
            if recommended is not None:
                k = summaries.index(recommended)
                if t2_i[k] == col:
                    ax.add_patch(plt.Rectangle((t1_i[k] - 0.5, th_i[k] - 0.5), 1, 1, fill=False, lw=2.0, ec="blue"))
            ax.set_xticks(range(n_t1), t1_labels, fontsize=7)
            ax.set_yticks(range(n_th), th_labels, fontsize=7)
            if row == 0:
                ax.set_title(f"T2 {t2_labels[col]} s", fontsize=9)
            if row == len(METRICS) - 1:
                ax.set_xlabel("T1 [s]", fontsize=8)
            if col == 0:
                ax.set_ylabel(f"{name}\nthreshold [mm]", fontsize=8)
        fig.colorbar(im, ax=axes[row, :].tolist(), shrink=0.9, pad=0.01)
    fig.suptitle(title, fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
