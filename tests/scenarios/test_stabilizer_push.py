"""Standing push recovery with the Stabilizer, and the capture-point flag when pushed past the threshold."""

import numpy as np
import pytest

from controller.layers.stabilizer import StabilizerParams
from tests.scenarios.helpers import make_system, tilt_deg

PUSH_S = 0.1  # the impulse is delivered as a constant force over 0.1 s


def push_and_watch(impulse_ns: np.ndarray, stabilizer: bool = True, seconds: float = 4.0,
                   emergency_step: bool = True):
    """Stand 3 s, push BODY with `impulse_ns` [N s], watch; returns (fallen, worst tilt, snapshots).
    `emergency_step` False: the AutoBalancer's capture-point emergency step (issue 13.3) is off."""
    system = make_system()
    loop = system.loop
    if not emergency_step:
        abc = loop.chain["abc"]
        loop.call(lambda: abc.set_params(abc.params.replaced(**{"emergency_step.enabled": False})))
    if not stabilizer:
        loop.call(lambda: loop.chain["st"].stop())
    loop.run_for(3.0)
    loop.call(lambda: loop.plant.push("BODY", np.asarray(impulse_ns) / PUSH_S, PUSH_S))
    snaps = [loop.step() for _ in range(int(seconds / loop.dt_control_s))]
    worst = max(tilt_deg(s.truth.base_quat_wxyz) for s in snaps)
    return snaps[-1].fallen, worst, snaps


#: Bounds are the measured figure times this (30 % margin): the simulation is deterministic on one machine;
#: the margin is for another machine's floating point and for small changes of the controller.
MARGIN = 1.3
#: [m] the CP error once the robot has settled: measured 0.4-2.0 mm over the pushes below (1.2-2.3 mm before
#: the F/T sensors' weight compensation took the weight about the world COM), margin 50 %.
SETTLED_CP_ERROR_M = 0.0030


@pytest.mark.parametrize("impulse, measured_tilt_deg", [((20.0, 0.0, 0.0), 2.68), ((0.0, 30.0, 0.0), 3.98),
                                                         ((-15.0, 0.0, 0.0), 2.31)],
                         ids=["forward-20Ns", "left-30Ns", "backward-15Ns"])
def test_a_push_on_body_is_absorbed_with_the_stabilizer_on(impulse, measured_tilt_deg):
    fallen, worst, snaps = push_and_watch(np.array(impulse))
    assert not fallen
    assert worst < MARGIN * measured_tilt_deg, f"worst tilt {worst:.2f} deg, measured {measured_tilt_deg} deg"
    # and it comes back: 4 s after the push the capture-point error is that of standing again (measured 0.4,
    # 0.9, 1.4 mm)
    assert snaps[-1].layers["st"].cp_error_norm < SETTLED_CP_ERROR_M


@pytest.mark.slow
@pytest.mark.parametrize("impulse, stabilizer, measured_tilt_deg", [
    ((26.0, 0.0, 0.0), True, 5.48), ((0.0, 40.0, 0.0), True, 11.29), ((0.0, -40.0, 0.0), True, 11.17),
    ((-20.0, 0.0, 0.0), True, 5.08),
    ((22.0, 0.0, 0.0), False, 4.16), ((0.0, 40.0, 0.0), False, 10.18), ((0.0, -40.0, 0.0), False, 10.19)],
    ids=["st-forward-26Ns", "st-left-40Ns", "st-right-40Ns", "st-backward-20Ns", "no-st-forward-22Ns",
         "no-st-left-40Ns", "no-st-right-40Ns"])
def test_the_largest_pushes_the_readme_claims_are_absorbed(impulse, stabilizer, measured_tilt_deg):
    # the table in docs/measurements/walking-and-balance.md (28 N s forward measured; 26 asserted), 20 N s
    # backward (21 falls), 40 N s sideways, 22 N s forward and 40 N s sideways without it (41 N s sideways falls
    # with it, same page). Sideways the robot
    # rocks on one sole edge (tilt up to 11 deg) and settles within 6-7 s.
    # without the Stabilizer the ankles alone (its capture point would start an emergency step, issue 13.3); with
    # it these pushes are absorbed without a step
    fallen, worst, snaps = push_and_watch(np.array(impulse), stabilizer=stabilizer, seconds=8.0,
                                          emergency_step=stabilizer)
    assert not fallen
    assert snaps[-1].layers["abc"].emergency_steps == ()
    assert worst < MARGIN * measured_tilt_deg, f"worst tilt {worst:.2f} deg, measured {measured_tilt_deg} deg"
    settled = max(s.layers["st"].cp_error_norm for s in snaps[-200:])  # the last second (measured 0.9-1.7 mm)
    assert settled < SETTLED_CP_ERROR_M


def test_the_capture_point_error_is_in_every_snapshot_and_the_flag_rises_past_the_threshold():
    fallen, _, snaps = push_and_watch(np.array([20.0, 0.0, 0.0]), seconds=2.0)
    errors = np.array([s.layers["st"].cp_error_norm for s in snaps])
    flags = np.array([s.layers["st"].emergency for s in snaps])
    threshold = snaps[0].layers["st"].cp_threshold_m
    # 1. before the push the error is tiny and the flag down
    assert errors[0] < 0.01 and not flags[0]
    # 2. the push drives the error past the threshold and the flag follows it
    assert errors.max() > threshold
    assert flags.any()
    over = errors > threshold
    assert flags[over].all()  # up whenever the error is over the threshold
    first = int(np.argmax(over))
    assert not flags[:first].any() and flags[first]  # rises at the first tick over it
    # and falls only once the error has stayed under half the threshold for the release time (hysteresis)
    params = StabilizerParams()
    n = round(params.cp_release_s / 0.005)
    for i in np.flatnonzero(flags[:-1] & ~flags[1:]) + 1:
        assert i >= n and (errors[i - n + 1:i + 1] < params.cp_release_ratio * threshold).all()
    assert snaps[-1].layers["st"].flag_rose_at is not None


@pytest.mark.slow
def test_the_stabilizer_absorbs_a_forward_push_that_topples_the_robot_without_it():
    # the ankles alone: without the Stabilizer the capture-point emergency step would catch this push (it does)
    impulse = np.array([26.0, 0.0, 0.0])
    fallen_with, _, _ = push_and_watch(impulse, stabilizer=True, emergency_step=False)
    fallen_without, _, _ = push_and_watch(impulse, stabilizer=False, emergency_step=False)
    assert not fallen_with
    assert fallen_without


def test_a_20ns_forward_push_settles_without_ringing():
    # issue 13.1: the capture-point error crosses the threshold once, the measured ZMP never reaches the heel
    # edge, and the error is under 10 mm from 1 s after its peak on. Measured: 1 crossing (4 before the
    # attitude estimate trusted the gyro while BODY turns and the standing pitch damping was 300), ZMP at
    # least 24.1 mm in front of the heel edge (it sat on it for 0.45 s before), 6.2 mm (62 mm before); with
    # the accelerometer's tilt instead of the soles' (before issue 13.2) 16.7 mm and 5.1 mm; with the soles'
    # tilt but the F/T sensors' weight compensation about the wrong COM, 26.5 and 6.0 mm.
    from controller.balance.capture_point import HRP2_RIGHT_SOLE

    fallen, _, snaps = push_and_watch(np.array([20.0, 0.0, 0.0]), seconds=3.0)
    assert not fallen
    errors = np.array([s.layers["st"].cp_error_norm for s in snaps])
    threshold = snaps[0].layers["st"].cp_threshold_m
    crossings = int(np.sum(np.diff((errors > threshold).astype(int)) == 1))
    assert crossings == 1
    ankle_x = snaps[0].reference.gait.p_rsole_world[0]
    zmp_from_ankle_x = np.array([s.zmp_world[0] for s in snaps]) - ankle_x
    heel_clearance_m = zmp_from_ankle_x.min() + HRP2_RIGHT_SOLE.rear_m
    assert heel_clearance_m > 0.0241 / MARGIN, f"measured ZMP {heel_clearance_m * 1e3:.1f} mm from the heel edge"
    peak = int(np.argmax(errors))
    late = errors[peak + int(1.0 / (snaps[1].time_s - snaps[0].time_s)):]
    assert late.max() < MARGIN * 0.0062, f"|CP error| {late.max() * 1e3:.1f} mm 1 s after its peak"
