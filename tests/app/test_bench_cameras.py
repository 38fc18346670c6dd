"""The camera benchmark reports what it timed (timing goals are the bench's figures, never asserted here)."""

import pytest

from app.lab.bench import run_bench
from app.lab.bench_cameras import run_camera_bench, run_recognition_bench


def test_the_camera_bench_reports_wall_times_of_the_narrow_pair_against_the_goal():
    r = run_camera_bench(renders=2)
    assert r["scenario"] == "camera" and r["renders"] == 2 and r["cameras"] == ["narrow_left", "narrow_right"]
    assert 0.0 < r["wall_s"]["median"] <= r["wall_s"]["max"]
    assert r["goal_s"] == 0.3 and isinstance(r["within_goal"], bool)


def test_the_camera_bench_takes_no_layer_selection():
    with pytest.raises(ValueError, match="cameras"):
        run_bench("camera", layers="seq")


def test_the_recognition_bench_finds_the_can_every_time_it_times_a_recognition():
    r = run_recognition_bench(recognitions=2)
    assert r["scenario"] == "recognition" and r["found"] == 2
    assert 0.0 < r["render_s"]["median"] <= r["wall_s"]["median"]


@pytest.mark.slow
def test_the_paced_recognition_bench_compares_the_lateness_without_and_with_recognitions():
    from app.lab.bench_cameras import run_recognition_paced_bench

    r = run_recognition_paced_bench(duration_s=3.0)
    assert r["scenario"] == "recognition-paced" and r["locate_can_runs"] >= 1
    assert r["found"] == r["locate_can_runs"]  # each run located the can on the table
    for part in ("without_recognition", "with_recognition"):
        assert r[part]["ticks"] >= 500  # ~3 s of 5 ms ticks (fewer only if the loop fell far behind)
        assert r[part]["lateness_p50_ms"] <= r[part]["lateness_p99_ms"] <= r[part]["lateness_max_ms"]
    assert len(r["lateness_max_ms_per_run"]) == r["locate_can_runs"]
