"""[MLC] IV-C 2, Fig. 12 / 13 (gamma): the door experiment. The left hand grasps the knob of a pull door; the
undisturbed pull opens it, a pushing plan (the paper's disturbance) meets the door stop and the capture-point
flag stops and reverts it before the robot tips backward."""

import pytest

from app.lab.experiments import EXPERIMENTS, run_experiment

#: The pull plan ends at -20 deg; the door follows the hand to about -19 deg.
DOOR_OPENED_DEG = -10.0


@pytest.mark.slow
def test_door_pull_opens_the_door_and_the_robot_stands(tmp_path):
    r = run_experiment("door", es=True, variant="pull", out_dir=tmp_path, plot=False)
    assert r.verdict == "stood"
    assert r.emergency_steps == 0  # no capture-point emergency step (issue 13.3)
    assert r.flag_time_s is None  # an undisturbed pull does not raise the flag
    assert r.outcome["door_angle_deg"] < DOOR_OPENED_DEG  # opened toward the robot by more than 10 deg
    assert r.faults == ()  # the run's own fault counter


@pytest.mark.slow
def test_door_push_plan_with_the_emergency_stopper_flags_inside_the_support_and_recovers(tmp_path):
    r = run_experiment("door", es=True, variant="push-plan", out_dir=tmp_path, plot=False)
    assert r.verdict == "stood"
    assert r.emergency_steps == 0  # no capture-point emergency step (issue 13.3)
    assert r.flag_time_s is not None and r.flag_time_s > 4.5  # during the push, which starts at 4.5 s
    assert r.edge_margin_at_flag_m > 0.0  # the actual CP was still inside the support polygon
    assert r.below_threshold_after_revert_s is not None and r.below_threshold_after_revert_s < 2.0
    assert abs(r.outcome["door_angle_deg"]) < 2.0  # the door stop held
    # no controller fault (a fault engages the HardEmergencyStopper, which would also keep the robot up)
    assert r.faults == ()


def test_door_experiment_has_the_push_plan_first_and_the_pull():
    assert EXPERIMENTS["door"].variants == ("push-plan", "pull")
    assert EXPERIMENTS["door"].scene == "door"
