"""The viewers benchmark runs a real console, watches it with camera and telemetry streams and reports the loop
(the figures themselves are the benchmark's, not this test's)."""

import pytest

from app.lab.bench_viewers import run_viewers_bench

pytestmark = pytest.mark.slow


def test_the_viewers_bench_watches_the_console_and_reports_the_loop():
    report = run_viewers_bench(duration_s=4.0, viewers=2, scene="default", baseline_s=2.0)
    assert report["errors"] == [], report["errors"]
    assert len(report["camera_received_hz"]) == 2 and min(report["camera_received_hz"]) > 1.0, report
    assert min(report["telemetry_received_hz"]) > 2.0, report
    assert 0 < report["camera_kB_per_frame"] < 100  # a 320 x 240 JPEG
    watched = report["loop_watched"]
    assert watched["ticks"] > 0.5 * 4.0 / 0.005 and watched["lateness_p99_ms_worst_window"] is not None
    assert report["loop_unwatched_before"]["ticks"] > 0
