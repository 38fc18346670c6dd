"""The Wilson interval: known values, the edges, bad input."""

import pytest

from app.lab.study.wilson import wilson_interval

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_known_values():
    lo, hi = wilson_interval(8, 10)
    assert lo == pytest.approx(0.4902, abs=1e-4) and hi == pytest.approx(0.9433, abs=1e-4)
    lo, hi = wilson_interval(10, 10)
    assert lo == pytest.approx(0.7225, abs=1e-4) and hi == 1.0
    assert wilson_interval(0, 5)[0] == 0.0


def test_no_trials_give_no_interval_and_impossible_counts_are_refused():
    assert wilson_interval(0, 0) is None
    with pytest.raises(ValueError, match="0..n"):
        wilson_interval(3, 2)
