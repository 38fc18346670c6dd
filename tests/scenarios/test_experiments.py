"""[MLC] IV-C wall-push-forward and wall-push-left (Fig. 8-10): the capture-point flag stops and reverts the push."""

import pytest

from app.lab.experiments import EXPERIMENTS, run_experiment


@pytest.mark.slow
def test_wall_push_forward_with_the_emergency_stopper_flags_before_the_edge_and_recovers(tmp_path):
    r = run_experiment("wall-push-forward", es=True, out_dir=tmp_path)
    assert r.verdict == "stood"
    assert r.emergency_steps == 0  # the revert alone suffices: no capture-point emergency step (issue 13.3)
    assert r.flag_time_s is not None
    assert r.edge_margin_at_flag_m > 0.0  # the actual CP was still inside the support polygon
    assert r.below_threshold_after_revert_s is not None and r.below_threshold_after_revert_s < 2.0
    assert (tmp_path / "wall-push-forward.csv").stat().st_size > 0
    assert (tmp_path / "wall-push-forward.png").stat().st_size > 0
    assert r.faults == ()  # no controller fault: the run's own counter


@pytest.mark.slow
def test_wall_push_forward_without_it_drives_the_capture_point_out_of_the_support_and_falls(tmp_path):
    r = run_experiment("wall-push-forward", es=False, out_dir=tmp_path, plot=False)
    # Fig. 10 (a): the error reaches the support-polygon edge (the CP leaves the polygon), then the fall
    assert r.min_edge_margin_m < 0.0
    assert r.verdict == "fell"
    # the capture-point emergency step (on by default) is taken once the CP has left the soles, and does not save
    # it: the stretched arms keep pushing on the wall (measured: 1 step, fell)
    assert r.emergency_steps == 1


@pytest.mark.slow
def test_wall_push_left_with_the_emergency_stopper_flags_inside_the_support_and_recovers(tmp_path):
    r = run_experiment("wall-push-left", es=True, out_dir=tmp_path, plot=False)
    assert r.verdict == "stood"
    assert r.emergency_steps == 0  # the revert alone suffices: no capture-point emergency step (issue 13.3)
    assert r.flag_time_s is not None and 3.0 < r.flag_time_s < 5.0  # during the 2 s push that starts at 3 s
    assert r.edge_margin_at_flag_m > 0.0  # the actual CP was still inside the support polygon
    assert r.below_threshold_after_revert_s is not None and r.below_threshold_after_revert_s < 2.0
    assert r.faults == ()  # no controller fault: the run's own counter


@pytest.mark.slow
def test_wall_push_left_without_it_leaves_the_robot_leaning_on_the_wall(tmp_path):
    r = run_experiment("wall-push-left", es=False, out_dir=tmp_path, plot=False)
    # the stretched arm keeps pushing: the capture point is pushed away from the wall and stays there
    assert r.peak_cp_error_m > 0.06
    assert r.below_threshold_after_revert_s is None  # never back below the threshold


def test_a_controller_fault_during_an_experiment_is_in_its_result(monkeypatch):
    from controller.layers.emergency_stopper import EmergencyStopper

    def broken(self, ctx, ref):
        if ctx.time_s > 2.55:  # after the 2.5 s settling, in the script
            raise RuntimeError("boom")
        return ref

    monkeypatch.setattr(EmergencyStopper, "tick", broken)
    r = run_experiment("wall-push-left", duration_s=0.1, plot=False, write_csv=False)
    assert r.faults == ("RuntimeError: boom",)
    assert r.verdict == "stood"  # the HardEmergencyStopper holds the robot: the verdict alone would not tell


def test_unknown_experiment_lists_the_available_ones():
    with pytest.raises(ValueError, match="wall-push-forward"):
        run_experiment("moon-walk")
    assert "wall-push-forward" in EXPERIMENTS and "wall-push-left" in EXPERIMENTS


def test_settling_time_counts_until_the_error_stays_below_the_threshold():
    import numpy as np

    from app.lab.experiments import settled_below_after_s

    t = np.arange(10) * 0.5
    err = np.array([0, 5, 1, 5, 1, 1, 5, 1, 1, 1], dtype=float)
    assert settled_below_after_s(t, err, 2.0, 1.0) == 2.5  # re-crossing at 3.0 s counts: below from 3.5 s
    assert settled_below_after_s(t, err, 2.0, 3.5) == 0.0
    assert settled_below_after_s(t, np.r_[err[:-1], 5.0], 2.0, 1.0) is None
