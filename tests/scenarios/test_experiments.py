"""[MLC] IV-C wall-push-forward (Fig. 8-10): the capture-point flag stops and reverts the push."""

import pytest

from app.experiments import EXPERIMENTS, run_experiment


@pytest.mark.slow
def test_wall_push_forward_with_the_emergency_stopper_flags_before_the_edge_and_recovers(tmp_path):
    r = run_experiment("wall-push-forward", es=True, out_dir=tmp_path)
    assert r.verdict == "stood"
    assert r.flag_time_s is not None
    assert r.edge_margin_at_flag_m > 0.0  # the actual CP was still inside the support polygon
    assert r.below_threshold_after_revert_s is not None and r.below_threshold_after_revert_s < 2.0
    assert (tmp_path / "wall-push-forward.csv").stat().st_size > 0
    assert (tmp_path / "wall-push-forward.png").stat().st_size > 0


@pytest.mark.slow
def test_wall_push_forward_without_it_drives_the_capture_point_out_of_the_support_and_falls(tmp_path):
    r = run_experiment("wall-push-forward", es=False, out_dir=tmp_path, plot=False)
    # Fig. 10 (a): the error reaches the support-polygon edge (the CP leaves the polygon), then the fall
    assert r.min_edge_margin_m < 0.0
    assert r.verdict == "fell"


def test_unknown_experiment_lists_the_available_ones():
    with pytest.raises(ValueError, match="wall-push-forward"):
        run_experiment("moon-walk")
    assert "wall-push-forward" in EXPERIMENTS
