"""EmergencyStopper in simulation: stop-motion freezes a playing plan while balance keeps working."""

import numpy as np

from tests.scenarios.helpers import MOVE_POSE_DEG, make_system, seq_call, tilt_deg


def test_stop_motion_during_a_10s_motion_holds_the_command_then_release_reaches_the_target():
    # hrpsys-notes 3.1 demoEmergencyStopJointAngle with the paper's EmergencyStopper (revert T1 over T2)
    system = make_system(auto_balancer=False)
    loop = system.loop
    es = system.chain["es"]
    target = np.deg2rad(MOVE_POSE_DEG)
    seq_call(system, "set_joint_angles", target, 10.0)
    loop.run_for(4.0)
    loop.call(lambda: es.stop_motion())
    loop.run_for(es.params.t2_s + 0.1)  # the revert is over
    held = loop.snapshot.q_cmd_rad.copy()
    commands = np.array([loop.step().q_cmd_rad for _ in range(600)])  # 3 s
    assert np.max(np.abs(commands - held)) < 1e-6
    assert loop.snapshot.layers["es"].stopped
    loop.call(lambda: es.release_motion())
    loop.run_until(lambda s: not s.layers["es"].recovering and not s.layers["seq"].interpolating, 10.0)
    snap = loop.run_for(0.5)
    assert np.allclose(snap.q_cmd_rad, target, atol=1e-7)
    assert not snap.fallen


def test_stop_motion_during_a_10s_wrench_command_holds_the_wrenches_then_release_reaches_them():
    # hrpsys-notes 3.1 demoEmergencyStopWrench: setWrenches([1]*24, 10), stopMotion, 3 s frozen, release
    system = make_system(auto_balancer=False)
    loop = system.loop
    es = system.chain["es"]
    target = np.ones(24)
    seq_call(system, "set_wrenches", target, 10.0)
    loop.run_for(4.0)
    moving = loop.snapshot.reference.wrenches.ravel().copy()
    assert 0.05 < moving.min() and moving.max() < 0.95  # on its way
    loop.call(lambda: es.stop_motion())
    loop.run_for(es.params.t2_s + 0.1)  # the revert is over
    held = loop.snapshot.reference.wrenches.ravel().copy()
    assert np.all(held < moving)  # reverted towards the plan of T1 earlier
    wrenches = np.array([loop.step().reference.wrenches.ravel() for _ in range(600)])  # 3 s
    assert np.max(np.abs(wrenches - held)) < 1e-9
    loop.call(lambda: es.release_motion())
    loop.run_until(lambda s: not s.layers["es"].recovering and not s.layers["seq"].interpolating, 10.0)
    snap = loop.run_for(1.0)
    assert np.allclose(snap.reference.wrenches.ravel(), target, atol=1e-7)
    assert not snap.fallen


def test_with_the_planned_motion_stopped_a_push_is_still_absorbed_by_the_stabilizer():
    system = make_system()
    loop = system.loop
    loop.run_for(3.0)
    loop.call(lambda: system.chain["es"].stop_motion())
    loop.run_for(0.5)
    assert loop.snapshot.layers["st"].active and loop.snapshot.layers["es"].stopped
    loop.call(lambda: loop.plant.push("BODY", np.array([200.0, 0.0, 0.0]), 0.1))  # 20 N s forward
    worst = max(tilt_deg(loop.step().truth.base_quat_wxyz) for _ in range(800))
    assert not loop.snapshot.fallen
    assert worst < 10.0
    assert loop.snapshot.layers["st"].cp_error_norm < 0.02
