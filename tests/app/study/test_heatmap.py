"""The heatmaps: a grid's own levels, a sample binned, a PNG with the recommended cell."""

import numpy as np
import pytest

from app.lab.study.analysis import ParamSummary
from app.lab.study.heatmap import BINS, levels, plot_heatmaps
from app.lab.study.space import EstopParams

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_few_distinct_values_are_their_own_levels_and_many_are_binned():
    index, labels, n = levels([40.0, 20.0, 40.0, 30.0])
    assert n == 3 and labels == ["20", "30", "40"] and index.tolist() == [2, 0, 2, 1]
    index, labels, n = levels(np.linspace(0.0, 1.0, 11))
    assert n == BINS and index[0] == 0 and index[-1] == BINS - 1 and len(labels) == BINS


def test_the_heatmap_png_is_written(tmp_path):
    grid = [(th, t1, t2) for th in (0.03, 0.06) for t1 in (0.5, 1.0) for t2 in (0.5, 1.0)]
    summaries = [ParamSummary(EstopParams(th, t1, t2), 4, 2, 2 if th < 0.06 else 1, 0, 4, 0, 2, 1e3 * (0.1 - th),
                              50.0 + 1e3 * th, 0.2 * t2, 0) for th, t1, t2 in grid]
    path = plot_heatmaps(summaries, tmp_path / "h.png", "test", summaries[1])
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10_000
