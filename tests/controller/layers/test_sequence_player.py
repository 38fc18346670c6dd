"""SequencePlayer: hrpsys samplerobot_sequence_player cases (hrpsys-notes 3.5) adapted to HRP-2."""

import numpy as np
import pytest

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.types import Reference
from controller.layers.sequence_player import SequencePlayer, SequencePlayerParams
from robot.generate import half_sitting_deg
from robot.names import JOINT_GROUPS, JOINT_NAMES, joint_index
from tests.controller.fakes import make_ctx

DT = 0.005
EPS = 1e-7

RESET_POSE = np.deg2rad(half_sitting_deg())


def pose(base=RESET_POSE, **changes_deg):
    q = np.array(base, dtype=float)
    for name, deg in changes_deg.items():
        q[joint_index(name)] = np.deg2rad(deg)
    return q


#: arms forward, elbows bent, chest and head pitched (all within HRP-2's joint limits)
MOVE_POSE = pose(RARM_JOINT0=-60, LARM_JOINT0=-60, RARM_JOINT3=-60, LARM_JOINT3=-60, CHEST_JOINT1=10,
                 HEAD_JOINT1=10)
LARM = np.array(JOINT_GROUPS["larm"])
RARM = np.array(JOINT_GROUPS["rarm"])
LARM_POS0 = np.deg2rad([15, 10, 0, -90, 0, 0, 10])  # elbow bent
LARM_POS1 = np.deg2rad([15, 10, 0, -6.6, 0, 0, 10])  # elbow nearly straight
CTX = make_ctx(dt=DT)


def make_player(**kw):
    return SequencePlayer(Reference.from_arrays(RESET_POSE), DT, **kw)


def run(player, seconds):
    """Step `seconds` of control periods; returns the last output."""
    out = player.last_output
    for _ in range(round(seconds / DT)):
        out = player.tick(CTX, out)
    return out


def wait(player, timeout_s=30.0):
    """hrpsys waitInterpolation: step until the player is idle; returns the last output."""
    out = player.last_output
    for _ in range(round(timeout_s / DT)):
        if not player.is_interpolating():
            return out
        out = player.tick(CTX, out)
    raise AssertionError("still interpolating after the timeout")


def wait_group(player, group, timeout_s=30.0):
    out = player.last_output
    for _ in range(round(timeout_s / DT)):
        if not player.is_interpolating_group(group):
            return out
        out = player.tick(CTX, out)
    raise AssertionError(f"group {group} still interpolating after the timeout")


def assert_joints(out, expected, eps=EPS):
    assert np.max(np.abs(out.q_rad - expected)) <= eps


def assert_between(out, a, b, eps=EPS):
    """hrpsys "between": every joint lies between the two poses ((z - y)(x - y) <= eps)."""
    assert np.all((a - out.q_rad) * (b - out.q_rad) <= eps)


def with_larm(q_larm):
    q = RESET_POSE.copy()
    q[LARM] = q_larm
    return q


# ---- 1. setJointAngles -------------------------------------------------------------------------


def test_set_joint_angles_reaches_the_pose_and_comes_back():
    seq = make_player()
    seq.set_joint_angles(MOVE_POSE, 1.0)
    assert seq.is_interpolating()
    assert_joints(wait(seq), MOVE_POSE)
    seq.set_joint_angles(RESET_POSE, 1.0)
    assert_joints(wait(seq), RESET_POSE)


def test_set_joint_angles_takes_the_given_time():
    seq = make_player()
    seq.set_joint_angles(MOVE_POSE, 1.0)
    out = run(seq, 1.0 - DT)
    assert seq.is_interpolating() and np.max(np.abs(out.q_rad - MOVE_POSE)) > EPS
    assert_joints(run(seq, DT), MOVE_POSE)
    assert not seq.is_interpolating()


def test_new_set_joint_angles_overrides_the_motion_in_progress():
    seq = make_player()
    seq.set_joint_angles(MOVE_POSE, 5.0)
    run(seq, 2.5)
    seq.set_joint_angles(RESET_POSE, 1.0)
    assert seq.status().remaining_s == pytest.approx(1.0)
    assert_joints(wait(seq), RESET_POSE)


def test_clear_joint_angles_stops_between_the_poses():
    seq = make_player()
    seq.set_joint_angles(MOVE_POSE, 5.0)
    run(seq, 2.5)
    seq.clear_joint_angles()
    assert not seq.is_interpolating()
    out = run(seq, 0.5)
    assert_between(out, RESET_POSE, MOVE_POSE)
    assert not np.allclose(out.q_rad, RESET_POSE) and not np.allclose(out.q_rad, MOVE_POSE)


def test_override_keeps_the_joint_stream_velocity_continuous():
    seq = make_player()
    seq.set_joint_angles(MOVE_POSE, 2.0)
    qs = [run(seq, DT).q_rad for _ in range(200)]
    seq.set_joint_angles(RESET_POSE, 1.0)
    qs += [run(seq, DT).q_rad for _ in range(200)]
    dq = np.diff(np.array(qs), axis=0)
    ddq = np.diff(dq, axis=0)
    assert np.max(np.abs(ddq)) < 0.05 * np.max(np.abs(dq))  # no velocity step at the switch


# ---- 2. setJointAnglesSequence -----------------------------------------------------------------


def test_set_joint_angles_sequence_ends_on_the_last_pose():
    seq = make_player()
    seq.set_joint_angles_sequence([MOVE_POSE, RESET_POSE, MOVE_POSE], [1.0, 1.0, 1.0])
    assert_joints(run(seq, 1.0), MOVE_POSE)  # via points are passed at their times
    assert_joints(run(seq, 1.0), RESET_POSE)
    assert_joints(wait(seq), MOVE_POSE)
    seq.set_joint_angles_sequence([RESET_POSE], [1.0])
    assert_joints(wait(seq), RESET_POSE)


def test_set_joint_angles_sequence_override_and_clear():
    seq = make_player()
    seq.set_joint_angles_sequence([MOVE_POSE, RESET_POSE, MOVE_POSE], [1.0, 1.0, 5.0])
    run(seq, 3.5)
    seq.set_joint_angles_sequence([RESET_POSE, MOVE_POSE, RESET_POSE], [1.0, 1.0, 1.0])
    assert_joints(wait(seq), RESET_POSE)
    seq.set_joint_angles_sequence([MOVE_POSE, RESET_POSE, MOVE_POSE], [1.0, 1.0, 5.0])
    run(seq, 3.5)
    seq.clear()
    assert_between(run(seq, 0.1), RESET_POSE, MOVE_POSE)


# ---- 3. setJointAngle --------------------------------------------------------------------------


def test_set_joint_angle_moves_one_joint_only():
    seq = make_player()
    seq.set_joint_angle("CHEST_JOINT0", np.deg2rad(10.0), 1.0)
    out = wait(seq)
    assert abs(out.q_rad[12] - np.deg2rad(10.0)) <= EPS
    assert_joints(out, pose(CHEST_JOINT0=10))
    seq.set_joint_angle("CHEST_JOINT0", 0.0, 1.0)
    assert_joints(wait(seq), RESET_POSE)


def test_set_joint_angle_leaves_the_other_joints_on_their_motion():
    seq = make_player()
    seq.set_joint_angles(MOVE_POSE, 2.0)
    run(seq, 1.0)
    seq.set_joint_angle("HEAD_JOINT1", np.deg2rad(-5.0), 0.5)
    out = run(seq, 0.5)
    assert abs(out.q_rad[joint_index("HEAD_JOINT1")] - np.deg2rad(-5.0)) <= EPS
    assert seq.is_interpolating()
    assert_joints(wait(seq), pose(MOVE_POSE, HEAD_JOINT1=-5))


# ---- 5.-7. setZmp, setBasePos/Rpy, setWrenches -------------------------------------------------


def test_set_zmp_reaches_the_zmp():
    seq = make_player()
    for zmp in ([-0.00081, 1.7e-5, -0.66815], [0.0302518, 0.000153, -0.562325]):
        seq.set_zmp(zmp, 1.0)
        assert np.max(np.abs(wait(seq).zmp_base - zmp)) <= EPS


def test_set_base_pos_and_rpy_reach_the_waist_pose():
    seq = make_player()
    for pos, rpy in (([0.000234, 0.000146, 0.66815], [-0.000245, -0.000862, 0.000195]),
                     ([-0.092492, -6.26e-5, 0.6318], [-0.000205, 0.348204, 0.000268])):
        seq.set_base_pos(pos, 1.0)
        seq.set_base_rpy(rpy, 1.0)
        out = wait(seq)
        assert np.max(np.abs(out.base_pos_world - pos)) <= 1e-5
        assert np.max(np.abs(out.base_rpy_rad - rpy)) <= 1e-5


def test_set_wrenches_accepts_4x6_and_24_values():
    seq = make_player()
    w = np.array([[1.0] * 6, [-2.0] * 6, [3.0] * 6, [-4.0] * 6])
    seq.set_wrenches(w, 1.0)
    assert np.max(np.abs(wait(seq).wrenches - w)) <= 1e-5
    seq.set_wrenches(np.zeros(24), 1.0)
    assert np.max(np.abs(wait(seq).wrenches)) <= 1e-5


# ---- 8. setJointAnglesOfGroup ------------------------------------------------------------------


def test_set_joint_angles_of_group_moves_only_that_group():
    seq = make_player()
    for p in (LARM_POS0, LARM_POS1):
        seq.set_joint_angles_of_group("larm", p, 1.0)
        assert seq.status().active_groups == ("larm",)
        assert_joints(wait_group(seq, "larm"), with_larm(p))


def test_group_override_and_clears_stop_between():
    seq = make_player()
    seq.set_joint_angles_of_group("larm", LARM_POS1, 1.0)
    wait_group(seq, "larm")
    seq.set_joint_angles_of_group("larm", LARM_POS0, 5.0)
    run(seq, 2.5)
    seq.set_joint_angles_of_group("larm", LARM_POS1, 1.0)
    assert_joints(wait_group(seq, "larm"), with_larm(LARM_POS1))
    # clearJointAnglesOfGroup
    seq.set_joint_angles_of_group("larm", LARM_POS0, 5.0)
    run(seq, 2.5)
    seq.clear_joint_angles_of_group("larm")
    assert not seq.is_interpolating_group("larm")
    assert_between(run(seq, 0.1), with_larm(LARM_POS1), with_larm(LARM_POS0))
    seq.set_joint_angles_of_group("larm", LARM_POS1, 5.0)
    assert_joints(wait_group(seq, "larm"), with_larm(LARM_POS1))
    # clearOfGroup(larm, 0)
    seq.set_joint_angles_of_group("larm", LARM_POS0, 5.0)
    run(seq, 2.5)
    seq.clear_of_group("larm", 0.0)
    assert_between(run(seq, 0.1), with_larm(LARM_POS1), with_larm(LARM_POS0))
    seq.set_joint_angles_of_group("larm", LARM_POS1, 1.0)
    assert_joints(wait_group(seq, "larm"), with_larm(LARM_POS1))


def test_clear_of_group_with_time_brakes_smoothly_to_rest():
    seq = make_player()
    seq.set_joint_angles_of_group("larm", LARM_POS0, 2.0)
    qs = [run(seq, DT).q_rad for _ in range(200)]
    seq.clear_of_group("larm", 0.5)
    assert seq.is_interpolating_group("larm")
    qs += [run(seq, DT).q_rad for _ in range(120)]
    dq = np.diff(np.array(qs), axis=0)
    assert np.max(np.abs(np.diff(dq, axis=0))) < 0.05 * np.max(np.abs(dq))
    assert np.all(dq[-10:] == 0.0) and not seq.is_interpolating()
    assert_between(run(seq, DT), with_larm(RESET_POSE[LARM]), with_larm(LARM_POS0))


def test_group_motion_and_whole_body_motion_interact_by_joint_sets():
    seq = make_player()
    seq.set_joint_angles(MOVE_POSE, 2.0)
    run(seq, 0.5)
    seq.set_joint_angles_of_group("larm", LARM_POS1, 1.0)  # larm leaves the whole-body motion
    out = wait(seq)
    expected = MOVE_POSE.copy()
    expected[LARM] = LARM_POS1
    assert_joints(out, expected)
    seq.set_joint_angles_of_group("rarm", RESET_POSE[RARM], 5.0)
    run(seq, 0.5)
    seq.set_joint_angles(RESET_POSE, 1.0)  # the whole-body command overrides the group motion
    assert seq.status().remaining_s == pytest.approx(1.0)
    assert_joints(wait(seq), RESET_POSE)


def test_added_group_can_be_played_and_removed():
    seq = make_player()
    seq.add_joint_group("necks", ["HEAD_JOINT0", "HEAD_JOINT1"])
    seq.set_joint_angles_of_group("necks", np.deg2rad([20.0, -10.0]), 1.0)
    assert_joints(wait_group(seq, "necks"), pose(HEAD_JOINT0=20, HEAD_JOINT1=-10))
    seq.remove_joint_group("necks")
    with pytest.raises(InvalidCommand, match="necks"):
        seq.set_joint_angles_of_group("necks", np.zeros(2), 1.0)


# ---- 9. setJointAnglesSequenceOfGroup ----------------------------------------------------------


def test_set_joint_angles_sequence_of_group():
    seq = make_player()
    seq.set_joint_angles_sequence_of_group("larm", [LARM_POS0, LARM_POS1, LARM_POS0], [1.0, 1.0, 1.0])
    assert_joints(wait_group(seq, "larm"), with_larm(LARM_POS0))
    seq.set_joint_angles_sequence_of_group("larm", [LARM_POS1, LARM_POS0, LARM_POS1], [1.0, 1.0, 1.0])
    assert_joints(wait_group(seq, "larm"), with_larm(LARM_POS1))
    # override after 3.5 s
    seq.set_joint_angles_sequence_of_group("larm", [LARM_POS0, LARM_POS1, LARM_POS0], [1.0, 1.0, 5.0])
    run(seq, 3.5)
    seq.set_joint_angles_sequence_of_group("larm", [LARM_POS1, LARM_POS0, LARM_POS1], [1.0, 1.0, 1.0])
    assert_joints(wait_group(seq, "larm"), with_larm(LARM_POS1))
    # clear
    seq.set_joint_angles_sequence_of_group("larm", [LARM_POS0, LARM_POS1, LARM_POS0], [1.0, 1.0, 5.0])
    run(seq, 3.5)
    seq.clear_joint_angles_of_group("larm")
    assert_between(run(seq, 0.1), with_larm(LARM_POS1), with_larm(LARM_POS0))
    seq.remove_joint_group("larm")
    assert "larm" not in seq.groups


# ---- 11. setTargetPose -------------------------------------------------------------------------


class FakeIk:
    """Answers with LARM_POS0 for any target and records the call."""

    def __init__(self):
        self.calls = []

    def __call__(self, group, q_current, base_pos, base_rpy, target_pos, target_rpy, frame):
        self.calls.append((group, q_current.copy(), base_pos.copy(), base_rpy.copy(), target_pos, target_rpy,
                           frame))
        q = q_current.copy()
        q[np.array(JOINT_GROUPS[group])] = LARM_POS0
        return q


def test_set_target_pose_plays_the_ik_solution_of_the_group():
    ik = FakeIk()
    seq = make_player(ik_solver=ik)
    seq.set_target_pose("larm:BODY", [0.3, 0.2, -0.1], [0.0, -0.5, 0.0], 2.0)
    group, q_current, _, _, target_pos, target_rpy, frame = ik.calls[-1]
    assert (group, frame) == ("larm", "BODY")
    assert np.allclose(q_current, RESET_POSE) and np.allclose(target_pos, [0.3, 0.2, -0.1])
    assert np.allclose(target_rpy, [0.0, -0.5, 0.0])
    assert seq.status().active_groups == ("larm",)
    assert_joints(wait(seq), with_larm(LARM_POS0))
    seq.set_target_pose("larm", [0.3, 0.2, 0.6], [0.0, 0.0, 0.0], 1.0)
    assert ik.calls[-1][0] == "larm" and ik.calls[-1][-1] is None


def test_set_target_pose_without_a_solver_is_an_invalid_state():
    seq = make_player()
    with pytest.raises(InvalidState, match="ik_solver"):
        seq.set_target_pose("larm", [0.3, 0.2, 0.6], [0.0, 0.0, 0.0], 1.0)


# ---- bad inputs --------------------------------------------------------------------------------


@pytest.mark.parametrize("call, match", [
    (lambda s: s.set_joint_angle("LARM_JOINT9", 0.1, 1.0), "valid joints: RLEG_JOINT0"),
    (lambda s: s.set_joint_angles_of_group("leftarm", LARM_POS0, 1.0), "valid groups: head, larm, lleg"),
    (lambda s: s.clear_of_group("leftarm", 0.0), "valid groups"),
    (lambda s: s.is_interpolating_group("leftarm"), "valid groups"),
    (lambda s: s.set_joint_angles(MOVE_POSE[:29], 1.0), r"shape \(30,\)"),
    (lambda s: s.set_joint_angles_of_group("larm", LARM_POS0[:6], 1.0), r"shape \(7,\)"),
    (lambda s: s.set_wrenches(np.zeros((4, 3)), 1.0), "wrenches"),
    (lambda s: s.set_base_pos([0.0, 0.0], 1.0), "pos_world"),
    (lambda s: s.set_joint_angles(np.where(np.arange(30) == 3, np.nan, MOVE_POSE), 1.0), r"finite.*\[3\]"),
    (lambda s: s.set_zmp([0.0, np.inf, 0.0], 1.0), "finite"),
    (lambda s: s.set_joint_angles(MOVE_POSE, 0.0), "time_s must be a finite number > 0"),
    (lambda s: s.set_joint_angles(MOVE_POSE, -1.0), "time_s"),
    (lambda s: s.set_base_rpy([0.0, 0.0, 0.1], float("nan")), "time_s"),
    (lambda s: s.clear_of_group("larm", -0.5), "time_s"),
    (lambda s: s.set_joint_angles_sequence([MOVE_POSE, RESET_POSE], [1.0]), "equal length"),
    (lambda s: s.set_joint_angles_sequence([MOVE_POSE, RESET_POSE], [1.0, 0.0]), r"times_s\[1\]"),
    (lambda s: s.set_joint_angles_sequence([], []), "non-empty"),
    (lambda s: s.set_joint_angles_sequence_of_group("larm", [LARM_POS0, MOVE_POSE], [1.0, 1.0]),
     r"q_seq_group_rad\[1\]"),
    (lambda s: s.add_joint_group("larm", ["LARM_JOINT0"]), "exists"),
    (lambda s: s.add_joint_group("grip", ["LHAND"]), "unknown joint 'LHAND'"),
    (lambda s: s.remove_joint_group("leftarm"), "valid groups"),
    (lambda s: s.set_target_pose("leftarm:BODY", [0, 0, 0], [0, 0, 0], 1.0), "valid groups"),
    (lambda s: s.set_target_pose("larm", [0, 0, 0], [0, 0, 0], 0.0), "time_s"),
])
def test_bad_input_raises_invalid_command_and_changes_nothing(call, match):
    seq = make_player(ik_solver=FakeIk())
    seq.set_joint_angles(MOVE_POSE, 2.0)
    run(seq, 0.5)
    ref = make_player()
    ref.set_joint_angles(MOVE_POSE, 2.0)
    run(ref, 0.5)
    groups = dict(seq.groups)
    with pytest.raises(InvalidCommand, match=match):
        call(seq)
    assert seq.groups.keys() == groups.keys()
    for _ in range(300):
        assert np.array_equal(run(seq, DT).q_rad, run(ref, DT).q_rad)
    assert_joints(wait(seq), MOVE_POSE)


def test_unknown_group_message_lists_every_valid_group():
    seq = make_player()
    with pytest.raises(InvalidCommand) as err:
        seq.clear_joint_angles_of_group("arms")
    assert all(g in str(err.value) for g in JOINT_GROUPS)


# ---- layer behaviour ---------------------------------------------------------------------------


def test_idle_player_holds_its_last_output_whatever_comes_in():
    seq = make_player()
    other = Reference.from_arrays(MOVE_POSE)
    out = seq.tick(CTX, other)
    assert out is seq.last_output
    assert_joints(out, RESET_POSE)


def test_status_reports_motion_and_remaining_time():
    seq = make_player()
    assert seq.status().to_dict() == {"enabled": True, "interpolating": False, "active_groups": [], "remaining_s": 0.0}
    seq.set_joint_angles_of_group("rarm", RESET_POSE[RARM] + 0.1, 3.0)
    seq.set_zmp([0.01, 0.0, 0.0], 1.0)
    run(seq, 1.0)
    st = seq.status()
    assert st.interpolating and st.active_groups == ("rarm",)
    assert st.remaining_s == pytest.approx(2.0)


def test_time_none_uses_the_hrpsys_average_velocity_rule():
    seq = make_player(params=SequencePlayerParams(default_avg_vel_rad_s=0.5, min_auto_time_s=1.0))
    seq.set_joint_angle("CHEST_JOINT1", 1.0, None)  # 1 rad at 0.5 rad/s
    assert seq.status().remaining_s == pytest.approx(2.0)
    seq.set_joint_angle("CHEST_JOINT1", 0.05, None)  # short moves take at least 1 s
    assert seq.status().remaining_s == pytest.approx(1.0)


def test_params_are_validated_with_their_range():
    with pytest.raises(InvalidCommand, match="default_avg_vel_rad_s"):
        SequencePlayerParams(default_avg_vel_rad_s=0.0)


def test_every_joint_name_is_accepted_by_set_joint_angle():
    seq = make_player()
    for name in JOINT_NAMES:
        seq.set_joint_angle(name, 0.0, 1.0)
    assert_joints(wait(seq), np.zeros(30))
