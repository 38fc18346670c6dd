"""Each behaviour against the fake operation layer and the fake command interface (unit): it drives its
point to the goal at its speed limit, reports progress, succeeds within its tolerance, and its commands go
through the command interface (refusals fail the run)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from behaviors.base import describe, params_from
from behaviors.causes import run_cause
from behaviors.registry import BEHAVIORS, make
from behaviors.stand import HALF_SITTING_RAD
from behaviors.steps import STEPS
from controller.core.errors import InvalidCommand, InvalidState, UnknownName
from tests.behaviors.fakes import harness

GRIP = "RARM_JOINT6"


def test_squat_lowers_the_waist_by_the_depth_on_a_minimum_jerk_plan_under_its_peak_speed():
    h = harness()
    h0 = h.op.p["waist"][2]
    rid = h.runner.run(make("squat", {"depth_m": 0.15, "speed_m_s": 0.05}))
    plan_s = 1.875 * 0.15 / 0.05
    heights = []
    for _ in range(int(plan_s / 2 / h.op.dt_s)):
        h.tick()
        heights.append(h.op.p["waist"][2])
    assert h0 - heights[-1] == pytest.approx(0.075, abs=1e-3)  # half the plan: half the way
    assert h.runner.get(rid).progress == pytest.approx(0.5, abs=0.01)
    assert max(-np.diff(heights)) / h.op.dt_s <= 0.05 + 1e-9
    status = h.run_until_done(rid)
    assert status.state == "succeeded"
    assert h0 - h.op.p["waist"][2] == pytest.approx(0.15, abs=1e-9)  # the rates sum to the whole move


def test_an_operator_waist_motion_during_a_squat_stays_on_top_of_it():
    h = harness()
    h0 = h.op.p["waist"][2]
    rid = h.runner.run(make("squat", {"depth_m": 0.1}))
    for _ in range(20):  # the operator's part: 0.5 mm a tick upward, 1 cm in all
        h.op.p["waist"] = h.op.p["waist"] + [0.0, 0.0, 0.0005]
        h.tick()
    status = h.run_until_done(rid)
    assert h0 - h.op.p["waist"][2] == pytest.approx(0.09, abs=1e-9)
    assert status.state == "failed" and "operator moved it" in status.message


def test_look_at_turns_the_gaze_onto_a_world_point():
    h = harness()
    h.op.feet_yaw = 0.3  # the feet frame is turned: the gaze is in it
    rid = h.runner.run(make("look_at", {"x_m": 1.0, "y_m": 1.0, "z_m": 0.4}))
    assert h.run_until_done(rid).state == "succeeded"
    head = h.op.p["head"]
    d = np.array([1.0, 1.0, 0.4]) - head
    assert h.op.gaze[1] + 0.3 == pytest.approx(math.atan2(d[1], d[0]), abs=math.radians(0.5))
    assert h.op.gaze[0] == pytest.approx(math.atan2(-d[2], math.hypot(d[0], d[1])), abs=math.radians(0.5))


@pytest.mark.parametrize("name, params", [("look_at", {"x_m": 1.0, "y_m": 1.0, "z_m": 0.4}),
                                          ("reach", {"x_m": 0.4, "y_m": -0.25, "z_m": 0.9})])
def test_a_goal_reached_only_in_the_reference_fails_while_the_collision_detector_holds(name, params):
    """The goal checks read the operation layer's reference; held by the CollisionDetector downstream, the
    robot did not follow (a relocation looked at the floor, measured): the behaviour fails and says why."""
    h = harness()
    rid = h.runner.run(make(name, params))
    h.op.collision_pairs = (("LARM_LINK3", "CHEST_LINK1"),)
    status = h.run_until_done(rid)
    assert status.state == "failed"
    assert "CollisionDetector holds" in status.message and "LARM_LINK3-CHEST_LINK1" in status.message


def test_reach_plans_a_line_whose_rates_sum_to_the_move_and_an_operator_offset_adds():
    h = harness()
    rid = h.runner.run(make("reach", {"hand": "lhand", "x_m": 0.4, "y_m": 0.2, "z_m": 0.9,
                                      "keep_orientation": False, "yaw_deg": 20.0}))
    status = h.run_until_done(rid)
    assert status.state == "succeeded", status.message
    np.testing.assert_allclose(h.op.p["lhand"], [0.4, 0.2, 0.9], atol=0.003)
    assert math.degrees(math.atan2(h.op.R["lhand"][1, 0], h.op.R["lhand"][0, 0])) == pytest.approx(20.0, abs=1.0)
    assert h.op.p["rhand"].tolist() == [0.3, -0.25, 0.8]  # the other hand is not touched


def test_an_operator_offset_during_a_reach_stays_on_top_of_it():
    h = harness()
    rid = h.runner.run(make("reach", {"x_m": 0.4, "y_m": -0.25, "z_m": 0.8}))
    for _ in range(50):  # the operator's part at the same point: 1 mm a tick upward
        h.op.p["rhand"] = h.op.p["rhand"] + [0.0, 0.0, 0.001]
        h.tick()
    status = h.run_until_done(rid)
    np.testing.assert_allclose(h.op.p["rhand"], [0.4, -0.25, 0.85], atol=1e-9)
    assert status.state == "failed" and "operator moved it" in status.message


def test_reach_that_the_op_layer_clamps_fails_saying_how_far_it_ended():
    h = harness()
    rid = h.runner.run(make("reach", {"x_m": 0.5, "y_m": -0.25, "z_m": 0.8}))
    original_tick = h.op.tick
    h.op.tick = lambda: (setattr(h.op, "pending", ({}, None)), original_tick())  # the IK moves nothing
    status = h.run_until_done(rid)
    assert status.state == "failed" and "ended 200.0 mm" in status.message and "IK limited" in status.message


def test_walk_to_sends_one_go_pos_relative_to_the_feet_frame_and_checks_where_it_ended():
    h = harness()
    h.op.feet_p = np.array([1.0, 0.0, 0.0])
    h.op.feet_yaw = math.pi / 2
    h.commands.walk_s = 4.0
    rid = h.runner.run(make("walk_to", {"x_m": 1.0, "y_m": 0.5, "theta_deg": 0.0}))
    name, x, y, theta = h.commands.log[0]
    assert name == "go_pos" and (x, y) == pytest.approx((0.5, 0.0)) and theta == pytest.approx(-math.pi / 2)
    status = h.run_until_done(rid)
    assert status.state == "succeeded" and status.result["error_m"] < 1e-9
    assert status.nominal_duration_s == pytest.approx(6.0)


def test_walk_to_walks_again_for_what_a_walk_left_as_the_feet_frame_measures_it():
    h = harness()
    h.commands.walk_s = 4.0
    h.commands.walk_gain = 1.04  # each walk ends 4 % long: 40 mm on the first, then 1.6 mm
    rid = h.runner.run(make("walk_to", {"x_m": 1.0}))
    status = h.run_until_done(rid)
    walks = [entry for entry in h.commands.log if entry[0] == "go_pos"]
    assert [w[1] for w in walks] == pytest.approx([1.0, -0.04])
    assert status.state == "succeeded" and status.result["corrections"] == 1 and "1 correction" in status.message
    assert status.result["error_m"] == pytest.approx(0.0016)
    assert status.nominal_duration_s == pytest.approx(4.0 + 2.0 + 4.0 + 2.0)  # each walk and its settling


@pytest.mark.parametrize("replanned, cause", [(False, "limit"), (True, "state")])
def test_walk_to_off_its_goal_says_whether_its_walk_was_replanned_by_another_command(replanned, cause):
    # soak seed 10114: the operator's goPos re-planned walk_to's walk, which then failed naming no cause
    h = harness()
    h.commands.walk_gain = 1.2  # lands 20 % long: 20 cm off the goal
    rid = h.runner.run(make("walk_to", {"x_m": 1.0, "corrections": 0}))
    if replanned:
        h.commands.plan_version += 1  # another client's goPos, as the AutoBalancer counts it
    status = h.run_until_done(rid)
    assert status.state == "failed" and "20.0 cm" in status.message, status.message
    assert run_cause(status.message) == cause, status.message


def test_walk_to_that_ends_off_the_goal_fails_after_its_corrections_and_a_cancel_stops_walking():
    h = harness()
    h.commands.op = None  # the fake does not walk
    rid = h.runner.run(make("walk_to", {"x_m": 1.0, "corrections": 2}))
    status = h.run_until_done(rid)
    assert status.state == "failed" and "100.0 cm" in status.message and "after 2 correction" in status.message
    assert sum(entry[0] == "go_pos" for entry in h.commands.log) == 3
    h.op.walking = True
    rid = h.runner.run(make("walk_to", {"x_m": 1.0}))
    h.tick(10)
    h.runner.cancel(rid)
    assert h.commands.log[-1] == ("walk_stop",)


def test_a_refused_command_refuses_the_run_with_the_reason():
    h = harness()
    h.commands.refuse = "goPos refused: the hard e-stop is engaged"
    with pytest.raises(InvalidState, match="e-stop"):
        h.runner.run(make("walk_to", {"x_m": 1.0}))


def test_stand_resets_the_operation_targets_and_interpolates_to_half_sitting_but_the_grippers():
    h = harness()
    rid = h.runner.run(make("stand", {"time_s": 1.0}))
    assert h.commands.log[0] == ("reset_operation_targets",)
    _, angles, time_s = h.commands.log[1]
    assert time_s == 1.0 and angles == HALF_SITTING_RAD and GRIP not in angles and len(angles) == 28
    assert h.run_until_done(rid).state == "succeeded"
    assert h.runner.get(rid).ended_s == pytest.approx(1.0, abs=0.011)


def _aligning(h, ends):
    """The fake's walks: each goPos walks 20 ticks, then the soles stand at the next of `ends` (lsole_from_rsole)."""
    ends, state = list(ends), {"soles": (0.30, 0.30, 0.0), "left": 0}
    view, go_pos, tick = h.op.view, h.commands.go_pos, h.op.tick

    def walk(x_m, y_m, theta_rad):
        state["left"] = 20
        return go_pos(x_m, y_m, theta_rad)

    def step():
        tick()
        if state["left"] > 0:
            state["left"] -= 1
            if state["left"] == 0:
                state["soles"] = ends.pop(0)

    h.commands.go_pos, h.op.tick = walk, step
    h.op.view = lambda: dataclasses.replace(view(), lsole_from_rsole=state["soles"], walking=state["left"] > 0)


@pytest.mark.parametrize("ends, walks, state", [
    ([(0.0, 0.19, 0.0)], 1, "succeeded"),
    ([(0.05, 0.25, 0.0), (0.0, 0.19, 0.0)], 2, "succeeded"),  # soak seed 10050: the first walk ended 6 cm off
    ([(0.05, 0.25, 0.0)] * 3, 3, "failed"),
])
def test_stand_walks_again_when_its_aligning_walk_ends_off_and_gives_up_after_three(ends, walks, state):
    h = harness()
    _aligning(h, ends)
    run = h.run_until_done(h.runner.run(make("stand", {"time_s": 1.0})))
    assert [e[0] for e in h.commands.log].count("go_pos") == walks
    assert run.state == state, run.message
    if state == "failed":
        assert run_cause(run.message) == "timeout" and "3 aligning walks" in run.message


@pytest.mark.parametrize("level_after_s, walks_at_s", [(0.0, 1.0), (2.5, 2.5), (9.0, 6.0)])
def test_stands_aligning_walk_waits_for_the_waist_to_come_level(level_after_s, walks_at_s):
    # soak seed 10167: after a motion stop's release the waist came back from 9 deg of roll over 2.8 s; the goPos
    # asked once the reset's 1 s blend was over was refused ("straighten the waist first")
    h = harness()
    _aligning(h, [(0.0, 0.19, 0.0)])
    c, s_ = math.cos(math.radians(9.0)), math.sin(math.radians(9.0))
    h.op.R["waist"] = np.array([[1.0, 0.0, 0.0], [0.0, c, -s_], [0.0, s_, c]])  # rolled 9 deg
    rid = h.runner.run(make("stand", {"time_s": 1.0}))
    while not any(e[0] == "go_pos" for e in h.commands.log) and h.op.time_s < 10.0:
        if h.op.time_s >= level_after_s:
            h.op.R["waist"] = np.eye(3)
        h.tick()
    assert h.op.time_s == pytest.approx(walks_at_s, abs=0.011)  # level, or LEVEL_WAIT_MAX_S after the reset's 1 s
    assert h.run_until_done(rid).state == "succeeded"


def test_stand_is_refused_while_walking():
    h = harness()
    h.op.walking = True
    with pytest.raises(InvalidState, match="walking"):
        h.runner.run(make("stand"))


def _gripper(h, blocked_deg=None):
    h.commands.limits[GRIP] = (math.radians(-60.0), math.radians(15.0))
    h.commands.q[GRIP] = math.radians(-60.0)
    if blocked_deg is not None:
        h.commands.blocked[GRIP] = math.radians(blocked_deg)


def test_grasp_on_an_object_squeezes_with_the_set_force_below_the_14_newton_limit():
    h = harness()
    _gripper(h, blocked_deg=-20.0)
    rid = h.runner.run(make("grasp", {"force_n": 8.0}))
    status = h.run_until_done(rid)
    assert status.state == "succeeded" and status.result["holding"] is True
    # a perfect servo against a rigid object: the command sits 8 N x 0.085 m / 50 N m/rad past the jaw
    q_cmd = h.commands.q_cmd[GRIP]
    assert math.degrees(q_cmd) == pytest.approx(-20.0 + math.degrees(8.0 * 0.085 / 50.0), abs=1e-6)
    assert status.result["force_n"] == pytest.approx(8.0, abs=1e-6)


def test_grasp_at_the_14_newton_limit_commands_the_jaw_shut_so_the_torque_cap_keeps_the_force():
    h = harness()
    _gripper(h, blocked_deg=-20.0)
    status = h.run_until_done(h.runner.run(make("grasp", {"force_n": 14.0})))
    assert status.state == "succeeded" and status.result["holding"] is True
    assert h.commands.q_cmd[GRIP] == pytest.approx(h.commands.joint(GRIP).upper_rad)
    assert status.result["force_n"] == pytest.approx(14.0, abs=1e-6)


def test_grasp_on_nothing_fails_unless_no_object_is_required():
    h = harness()
    _gripper(h)
    assert "nothing" in h.run_until_done(h.runner.run(make("grasp"))).message
    h = harness()
    _gripper(h)
    status = h.run_until_done(h.runner.run(make("grasp", {"require_object": False})))
    assert status.state == "succeeded" and status.result["holding"] is False


def test_release_opens_the_gripper_and_a_second_gripper_command_on_the_same_hand_is_refused():
    h = harness()
    _gripper(h)
    h.commands.q[GRIP] = math.radians(10.0)
    rid = h.runner.run(make("release"))
    with pytest.raises(InvalidState, match=r"rhand.gripper.*release"):
        h.runner.run(make("grasp"))
    h.runner.run(make("grasp", {"hand": "lhand"}))  # the other hand is free
    assert h.run_until_done(rid).state == "succeeded"
    assert math.degrees(h.commands.q[GRIP]) == pytest.approx(-60.0)


def test_sequence_runs_its_steps_in_order_and_fails_naming_the_failing_step():
    h = harness()
    _gripper(h)
    seq = make("sequence", {"steps": [{"behavior": "squat", "params": {"depth_m": 0.05}},
                                       {"behavior": "reach", "params": {"z_m": 0.85}},
                                       {"behavior": "grasp"}]})
    assert set(seq.resources()) == {"waist", "rhand", "rhand.gripper"}
    rid = h.runner.run(seq)
    status = h.run_until_done(rid)
    assert status.state == "failed" and status.message.startswith("step 2 (grasp) failed: the jaw closed on nothing")
    assert "0.squat" in status.result and "1.reach" in status.result
    assert h.op.p["rhand"][2] == pytest.approx(0.85, abs=0.003)


def test_sequence_progress_counts_steps():
    h = harness()
    rid = h.runner.run(make("sequence", {"steps": [{"behavior": "squat", "params": {"depth_m": 0.05}},
                                                    {"behavior": "squat", "params": {"depth_m": -0.05}}]}))
    seq = h.runner._running[rid].behavior
    for _ in range(2000):
        if seq.index == 1:
            break
        h.tick()
    assert h.runner.get(rid).progress == pytest.approx(0.5, abs=1e-3)
    assert h.run_until_done(rid).state == "succeeded"


@pytest.mark.parametrize(("name", "params", "match"), [
    ("squat", {"depth_m": 0.5}, r"params.depth_m: 0.5 m is outside the allowed range \[-0.05, 0.25\] m"),
    ("squat", {"depth": 0.1}, r"params.depth: unknown parameter of SquatParams; valid: \['depth_m'"),
    ("squat", {"depth_m": "deep"}, r"params.depth_m: must be a number"),
    ("reach", {"hand": "head"}, r"params.hand: 'head' is not one of \['rhand', 'lhand'\]"),
    ("grasp", {"force_n": 20.0}, r"params.force_n: 20 N is outside the allowed range \[1, 14\] N"),
    ("sequence", {"steps": []}, r"steps: give 1..20 steps"),
    ("sequence", {"steps": [{"behavior": "fly"}]}, r"unknown behaviour 'fly'"),
    ("sequence", {"steps": [{"behavior": "squat", "params": {"depth_m": 1.0}}]}, r"steps.0.params.depth_m"),
])
def test_bad_parameters_are_refused_naming_the_field(name, params, match):
    with pytest.raises(InvalidCommand, match=match):
        make(name, params)


def test_unknown_behaviours_list_the_valid_names():
    valid = (r"valid: \['approach_table', 'follow_arc', 'grasp', 'locate_can', 'locate_handle', 'locate_trash', "
             r"'locate_trash_box', 'look_at', 'open_door', 'reach', 'recognise', 'release', 'sequence', 'squat', "
             r"'stand', 'take_can', 'throw_can', 'walk_to'\]")
    with pytest.raises(UnknownName, match=valid):
        make("dance")


def test_a_sequence_may_hold_every_behaviour_but_a_sequence():
    assert set(STEPS) == set(BEHAVIORS) - {"sequence"}
    with pytest.raises(InvalidCommand, match=r"steps.0.behavior: a sequence cannot contain a sequence"):
        make("sequence", {"steps": [{"behavior": "sequence"}]})


def test_every_behaviour_describes_its_parameters_with_units_and_ranges():
    for name, cls in BEHAVIORS.items():
        d = describe(cls)
        assert d["name"] == name and d["summary"]
        for p in d["params"]:
            assert "unit" in p and p["type"] in ("number", "integer", "boolean", "string", "array"), (name, p)
    squat = {p["name"]: p for p in describe(BEHAVIORS["squat"])["params"]}
    assert squat["depth_m"] == {"name": "depth_m", "type": "number", "default": 0.15, "unit": "m", "min": -0.05,
                                "max": 0.25, "doc": "how far the waist goes down (negative: up)"}
    assert params_from(BEHAVIORS["squat"].Params, {"depth_m": 0.1}).depth_m == 0.1
