"""app/lab/stats.py: latency percentiles."""

import pytest

from app.lab.stats import percentiles_ms

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_no_samples_reports_only_the_count():
    assert percentiles_ms([]) == {"n": 0}


def test_percentiles_are_nearest_rank_samples():
    values = [float(v) for v in range(100, 0, -1)]  # 100 ... 1, unsorted on purpose
    assert percentiles_ms(values) == {"n": 100, "p50_ms": 51.0, "p99_ms": 100.0, "max_ms": 100.0}


def test_values_are_rounded_to_a_microsecond():
    assert percentiles_ms([1.23456])["p50_ms"] == 1.235
