"""[MLC] IV-C 2 valve (Fig. 11, 13 alpha/beta): the turn planned from the recognised valve turns it; planned
from a disturbed recognition, the capture-point flag stops and reverts it before the CP leaves the feet."""

import math

import numpy as np
import pytest

from app.lab.experiments import EXPERIMENTS, run_experiment
from app.lab.experiments import valve as V
from app.lab.experiments.common import Rig
from app.service import OperatorService
from app.service.local import LocalRobot


@pytest.mark.slow
def test_undisturbed_the_robot_stands_and_turns_the_valve_by_a_third_of_the_planned_90_deg_or_more(tmp_path):
    r = run_experiment("valve", variant="undisturbed", out_dir=tmp_path, plot=False)
    assert r.verdict == "stood"
    assert r.emergency_steps == 0  # no capture-point emergency step (issue 13.3)
    assert r.flag_time_s is None  # the planned turn itself does not raise the flag
    assert V.PLANNED_TURN_DEG == pytest.approx(90.0)
    # measured ~80 deg: the impedance lets the hand lag the plan by the valve's friction / K
    assert r.outcome["valve_angle_deg"] >= 30.0
    assert r.faults == ()  # the run's own fault counter


@pytest.mark.slow
@pytest.mark.parametrize("variant", ["disturbed-forward", "disturbed-left"])
def test_disturbed_the_flag_rises_inside_the_support_and_the_error_recovers_after_the_revert(variant, tmp_path):
    r = run_experiment("valve", variant=variant, out_dir=tmp_path)
    assert r.verdict == "stood"
    assert r.emergency_steps == 0  # no capture-point emergency step (issue 13.3)
    assert r.flag_time_s is not None
    assert r.edge_margin_at_flag_m > 0.0  # the actual CP was still inside the support polygon
    assert r.below_threshold_after_revert_s is not None and r.below_threshold_after_revert_s < 2.0
    assert (tmp_path / f"valve-{variant}.png").stat().st_size > 0
    # no controller fault (a fault engages the HardEmergencyStopper, which would also keep the robot up)
    assert r.faults == ()


def valve_rig() -> Rig:
    robot = LocalRobot("valve")
    return Rig(OperatorService(robot), robot)


def test_the_disturbances_are_the_papers_and_only_move_the_recognition():
    rig = valve_rig()
    true = V.recognise_valve(rig)
    for variant, d in (("disturbed-forward", (0.13113, 0.0, 0.03292)), ("disturbed-left", (0.0, 0.19454, 0.0))):
        seen = V.recognise_valve(rig, V.DISTURBANCE_WORLD_M[variant])
        np.testing.assert_allclose(seen.centre_world - true.centre_world, d, atol=1e-12)
    np.testing.assert_allclose(true.centre_world, rig.plant.data.body("valve").xpos)
    assert EXPERIMENTS["valve"].variants[0] == "disturbed-forward"  # Fig. 11 (a-1), the headline case
    assert EXPERIMENTS["valve"].duration_s <= 17.5  # an 8 s walk to the stance, 9.3 s of manipulation


def test_the_planned_grasp_puts_the_rim_between_the_jaws_on_the_recognised_circle():
    valve = V.recognise_valve(valve_rig())
    for psi_deg in V.ARC_PSI_DEG:
        p_rim, R = V.rim_frame(valve, math.radians(psi_deg))
        assert np.linalg.norm(p_rim - valve.centre_world) == pytest.approx(V.VALVE_RING_RADIUS_M)
        assert abs(R[:, 1] @ (p_rim - valve.centre_world)) < 1e-12  # the hand's y axis along the rim
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
