"""ImpedanceController in simulation: a steady force on the hand displaces it by F/K; smooth start/stop."""

import numpy as np

from tests.scenarios.helpers import make_system, pose_deg, seq_call

REACH = np.deg2rad(pose_deg(RARM_JOINT0=-60, RARM_JOINT3=-60))


def hand_site(loop):
    """The simulated hand in the BODY frame: the impedance acts on the arm relative to the planned body,
    while the balance layers lean the whole body against the push."""
    d, m = loop.plant.data, loop.plant.model
    body = m.body("BODY").id
    R = d.xmat[body].reshape(3, 3)
    return R.T @ (d.site_xpos[m.site("rarm_end").id] - d.xpos[body])


def test_a_steady_20_newton_push_on_the_hand_displaces_it_by_f_over_k():
    system = make_system()
    loop = system.loop
    ic = system.chain["ic"]
    seq_call(system, "set_joint_angles", REACH, 1.5)
    loop.run_for(3.0)
    loop.call(lambda: ic.start("rarm"))
    loop.run_for(2.5)
    before = hand_site(loop)
    k = ic.params["rarm"].k_p
    force = np.array([20.0, 0.0, 0.0])  # pushing the hand forward
    loop.call(lambda: loop.plant.push("RARM_LINK5", force, 5.0))
    snap = loop.run_for(4.5)
    moved = hand_site(loop) - before
    expected = 20.0 / k  # 0.05 m
    # the commanded deviation and the simulated hand both within 10 % of F / K, along the push
    assert abs(snap.layers["ic"].rarm.displacement_m[0] - expected) < 0.1 * expected
    assert abs(moved[0] - expected) < 0.1 * expected
    assert abs(moved[1]) < 0.3 * expected and abs(moved[2]) < 0.3 * expected
    assert not snap.fallen


def test_starting_and_stopping_never_jumps_a_joint_command_by_half_a_degree():
    system = make_system()
    loop = system.loop
    ic = system.chain["ic"]
    seq_call(system, "set_joint_angles", REACH, 1.5)
    loop.run_for(3.0)
    cmds = []
    loop.call(lambda: ic.start("rarm"))
    cmds += [loop.step().q_cmd_rad for _ in range(500)]
    loop.call(lambda: ic.stop("rarm"))
    cmds += [loop.step().q_cmd_rad for _ in range(500)]
    steps = np.abs(np.diff(np.array(cmds), axis=0))
    assert np.degrees(steps.max()) < 0.5
    assert not loop.snapshot.layers["ic"].rarm.active


def test_no_force_no_deviation_and_wrong_start_stop_are_invalid_states():
    import pytest

    from controller.core.errors import InvalidState

    system = make_system()
    loop = system.loop
    ic = system.chain["ic"]
    loop.run_for(2.5)
    loop.call(lambda: ic.start("larm"))
    snap = loop.run_for(2.5)
    assert np.linalg.norm(snap.layers["ic"].larm.displacement_m) < 0.005  # the hand's own weight is removed
    with pytest.raises(InvalidState, match="already active"):
        loop.call(lambda: ic.start("larm"))
    with pytest.raises(InvalidState, match="not active"):
        loop.call(lambda: ic.stop("rarm"))


def test_the_gripper_follows_its_commands_while_the_impedance_controller_runs():
    from robot.names import joint_index

    system = make_system()
    loop = system.loop
    seq_call(system, "set_joint_angles", REACH, 1.5)
    loop.run_for(3.0)
    loop.call(lambda: system.chain["ic"].start("rarm"))
    loop.run_for(1.5)
    gripper = joint_index("RARM_JOINT6")
    target_rad = REACH[gripper] - np.deg2rad(20.0)  # close by 20 deg
    seq_call(system, "set_joint_angle", "RARM_JOINT6", target_rad, 1.0)
    snap = loop.run_for(1.5)
    assert abs(snap.q_cmd_rad[gripper] - target_rad) < 1e-6
    assert abs(loop.plant.data.qpos[loop.plant.model.joint("RARM_JOINT6").qposadr[0]] - target_rad) < np.deg2rad(1.0)

