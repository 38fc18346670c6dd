"""The checker catches each invariant's violation from synthetic answers and states, and flags nothing on
answers and states that keep them."""

from __future__ import annotations

import pytest

from app.lab.campaign.checker import Checker, Expectation, run_cause

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def state(time_s: float, tick: int | None = None, fallen: bool = False, **emergency) -> dict:
    e = {"hard_stop": False, "motion_stop": False, "motion_stop_time": None, "walking_stop": False, **emergency}
    return {"time": time_s, "tick": round(time_s / 0.005) if tick is None else tick, "fallen": fallen,
            "walking": False, "emergency": e}


def invariants(c: Checker) -> list[int]:
    return [v.invariant for v in c.violations]


# ---- 1 -------------------------------------------------------------------------------------------------------
def test_a_fall_after_pushes_inside_the_envelope_is_caught_once():
    c = Checker()
    c.state(state(1.0))
    c.push(15.0, 20.0)
    c.state(state(2.0, fallen=True))
    c.state(state(2.1, fallen=True))
    assert invariants(c) == [1] and "15.0 N s" in c.violations[0].detail


def test_a_fall_after_a_push_beyond_the_envelope_is_no_violation_nor_after_a_reset_a_new_one():
    c = Checker()
    c.push(30.0, 20.0)
    c.state(state(2.0, fallen=True))
    assert invariants(c) == []
    c.reset()
    c.state(state(3.0, fallen=True))
    assert invariants(c) == [1]


# ---- 2 -------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("status", "body"), [
    (409, {"detail": "refused", "reason": "no_reason_we_know"}),
    (409, {"detail": "refused"}),
    (423, {"detail": "locked", "reason": "locked"}),  # no holder
    (422, {"detail": "x: bad", "field": "x"}),  # the grammar sends valid bodies only
    (404, {"detail": "no such thing"}),
    (409, "plain text"),
])
def test_a_refusal_without_a_cause_from_the_closed_set_is_caught(status, body):
    c = Checker()
    c.answer("POST /api/x", status, body)
    assert invariants(c) == [2]


@pytest.mark.parametrize(("status", "body"), [
    (200, {"ok": True}),
    (409, {"detail": "go_pos refused: the robot has fallen", "reason": "fallen"}),
    (409, {"detail": "motion is not stopped", "reason": "state"}),
    (423, {"detail": "held by 'b'", "reason": "locked", "holder": "b"}),
])
def test_an_answer_or_a_refusal_naming_its_cause_is_not_flagged(status, body):
    c = Checker()
    c.answer("POST /api/x", status, body)
    assert invariants(c) == []


def test_a_stream_refusal_needs_a_reason_too():
    c = Checker()
    c.ack("s", {"ok": False, "ignored": True, "reason": "hard_stop"})
    c.ack("s", {"ok": True, "seq": 3})
    assert invariants(c) == []
    c.ack("s", {"ok": False, "detail": "no"})
    assert invariants(c) == [2]


@pytest.mark.parametrize(("message", "cause"), [
    ("look_at stopped at t = 3.105 s: the motion stop (EmergencyStopper) is latched, raised by ...", "stop"),
    ("cancelled by the operator", "cancel"),
    ("cancelled: the hard e-stop was engaged", "stop"),
    ("cancelled: the simulation was reset", "reset"),
    ("overran its nominal duration of 2.00 s by 50 % (3.01 s)", "timeout"),
    ("rhand ended 40.0 mm and 3.0 deg from the goal (the IK limited it, or the operator moved it)", "limit"),
    ("the jaw closed on nothing", "perception"),
    # the campaign with the foot points (seeds 1015, 1019): a walk refused, a foot lifted; stand's own timeouts
    ("step 1 (stand) refused: stand refused: the robot is walking; stop it first", "state"),
    ("Refused: goPos: the lfoot is lifted (its operational point); goPos once it is down", "state"),
    ("timeout: the aligning steps did not start within 0.5 s", "timeout"),
    # the soak (seed 10019): stand's aligning walk asked while the robot balanced a disturbance
    ("Refused: goPos: the capture-point flag is up (the robot is balancing a disturbance); goPos again once it "
     "drops (status: st.emergency false)", "state"),
    # the soak (seeds 10039, 10050): a walk refused while the waist's tilt leaves a knee too little range
    ("step 1 (walk_to) refused: goPos: LLEG_JOINT3 is 6.5 deg from its limit (the waist's tilt) and walking needs "
     "12 deg; straighten the waist first", "limit"),
    # the soak (seed 10114): walk_to's walk re-planned by the operator's goPos; or its footsteps as planned
    ("step 0 (walk_to) failed: stopped 11.7 cm and 30.6 deg from the goal (tolerance 0.99 cm, 27.4684 deg) after 0 "
     "correction(s): its walk was re-planned by another command meanwhile (goPos, goVelocity, footsteps, a "
     "catching step or goStop)", "state"),
    ("stopped 1.5 cm and 1.0 deg from the goal (tolerance 1 cm, 3 deg) after 0 correction(s): the footsteps landed "
     "as planned: the walk's accuracy limit", "limit"),
    # the soak (seed 10303): stand refused a stance only just wider than a closing step leaves
    ("Refused: closeStance: the feet stand 0.430 m apart across; it closes 0.34-0.43 m (narrower: goPos walks from "
     "there; wider: with the COM over one foot the far leg's hip roll reaches its limit)", "limit"),
    ("stopped 5.0 cm and 1.0 deg from the goal (tolerance 3 cm, 3 deg) after 2 correction(s)", None),
    ("TypeError: unsupported operand", None),
])
def test_a_runs_message_names_a_cause_from_the_closed_set_or_none(message, cause):
    assert run_cause(message) == cause


def test_a_failed_run_without_a_cause_is_caught_once_and_a_succeeded_one_never():
    c = Checker()
    run = {"id": 3, "behavior": "walk_to", "state": "failed", "message": "TypeError: x", "ended_s": 4.0}
    c.run(run)
    c.run(run)
    c.run({"id": 4, "behavior": "stand", "state": "succeeded", "message": "standing"})
    assert invariants(c) == [2]


def test_a_behaviour_started_under_the_motion_stop_is_caught():
    c = Checker()
    latched = {"motion_stop": True, "motion_stop_reason": "operator"}
    c.behavior_started("look_at", 409, {"detail": "refused", "reason": "motion_stop"}, latched)
    c.behavior_started("look_at", 200, {"id": 1}, {"motion_stop": False})
    assert invariants(c) == []
    c.behavior_started("look_at", 200, {"id": 2}, latched)
    c.behavior_started("squat", 409, {"detail": "the point is driven", "reason": "state"}, latched)
    assert invariants(c) == [2, 2]


# ---- 3 and 4 -----------------------------------------------------------------------------------------------------
def estop_expectation(tick: int) -> Expectation:
    return Expectation(3, "e-stop not engaged", lambda s: s["emergency"]["hard_stop"], 10.0,
                       frozenset({"estop_release"}), from_tick=tick, first_only=True)


def test_an_estop_answered_ok_and_not_engaged_on_the_first_state_at_its_tick_is_caught():
    c = Checker()
    c.expect(estop_expectation(200))
    c.state(state(0.9, tick=180))  # published before the answer's tick: not yet
    assert invariants(c) == []
    c.state(state(1.0, tick=200))
    assert invariants(c) == [3]


def test_an_estop_engaged_at_its_tick_or_released_after_is_not_flagged():
    c = Checker()
    c.expect(estop_expectation(200))
    c.state(state(1.0, tick=200, hard_stop=True))
    c.expect(estop_expectation(300))
    c.acted("estop_release")
    c.state(state(1.5, tick=300))
    assert invariants(c) == [] and c.expectations == []


def test_an_ok_not_applied_by_its_deadline_is_caught_and_one_applied_is_not():
    c = Checker()
    c.expect(Expectation(4, "release not applied", lambda s: not s["emergency"]["hard_stop"], 2.0))
    c.state(state(1.5, hard_stop=True))
    assert invariants(c) == []
    c.state(state(2.5, hard_stop=True))
    assert invariants(c) == [4]
    c.expect(Expectation(4, "release not applied", lambda s: not s["emergency"]["hard_stop"], 4.0))
    c.state(state(3.0))
    assert invariants(c) == [4] and c.expectations == []


# ---- 5 -------------------------------------------------------------------------------------------------------
def test_a_5xx_a_dead_robot_and_a_late_paced_tick_are_caught_and_max_speed_lateness_is_not():
    c = Checker()
    c.answer("GET /api/state", 500, {"detail": "internal error"})
    c.health({"robot_alive": False, "exit_reason": "killed"})
    c.timing({"paced": True, "lateness_max_ms": 2.5})
    assert invariants(c) == [5, 5, 5]
    c = Checker()
    c.health({"robot_alive": True})
    c.timing({"paced": True, "lateness_max_ms": 1.9})
    c.timing({"paced": False, "lateness_max_ms": 40.0})
    assert invariants(c) == []


# ---- 6 -------------------------------------------------------------------------------------------------------
HALF = {"RLEG_JOINT2": -26.0, "RLEG_JOINT3": 50.0, "RARM_JOINT6": 0.0}


def test_stand_that_fails_or_leaves_a_joint_off_half_sitting_is_caught():
    c = Checker()
    c.back_to_half_sitting(None, HALF, HALF, fallen=False)
    c.back_to_half_sitting({"state": "failed", "message": "x"}, HALF, HALF, fallen=False)
    c.back_to_half_sitting({"state": "succeeded"}, {**HALF, "RLEG_JOINT3": 40.0}, HALF, fallen=False)
    c.back_to_half_sitting({"state": "refused (409)", "message": "goPos: the feet stand 0.404 m apart"}, HALF, HALF,
                           fallen=False)
    assert invariants(c) == [6, 6, 6, 6] and "RLEG_JOINT3 -10.0 deg" in c.violations[2].detail
    assert "(failed: x)" in c.violations[1].detail and "refused (409): goPos: the feet" in c.violations[3].detail


def test_stand_back_at_half_sitting_the_grippers_aside_or_a_fallen_robot_is_not_flagged():
    c = Checker()
    c.back_to_half_sitting({"state": "succeeded"}, {**HALF, "RLEG_JOINT3": 51.0, "RARM_JOINT6": -50.0}, HALF,
                           fallen=False)
    c.back_to_half_sitting(None, {}, HALF, fallen=True)
    assert invariants(c) == []


def test_a_stand_that_fails_after_a_push_beyond_the_envelope_is_listed_not_counted_and_within_it_is_caught():
    # soak seeds 10014, 10070, 10079, 10157: pushed while the hard e-stop held the robot frozen (envelope 0), left on
    # one foot or tilted; beyond the envelope the invariants promise nothing, as invariant 1 for a fall
    c = Checker()
    c.push(8.4, 20.0)  # inside the standing envelope: stand must still bring it back
    c.back_to_half_sitting({"state": "failed", "message": "stopped by the flag"}, HALF, HALF, fallen=False)
    assert invariants(c) == [6] and c.beyond_stands == []
    c.push(7.6, 0.0)  # while frozen: beyond
    c.back_to_half_sitting({"state": "failed", "message": "stopped by the flag"}, HALF, HALF, fallen=False)
    assert invariants(c) == [6]
    assert len(c.beyond_stands) == 1 and "stopped by the flag" in c.beyond_stands[0]["detail"]
    assert c.beyond_stands[0]["pushes"] == [(c.time_s, 7.6, 0.0)]
    c.reset()  # a new stretch: the push before is forgotten
    c.back_to_half_sitting(None, HALF, HALF, fallen=False)
    assert invariants(c) == [6, 6]


def test_a_controller_fault_is_caught_once_while_it_shows():
    c = Checker()
    c.state(state(1.0))
    for t in (2.0, 2.005, 2.01):
        c.state(state(t, fault="InvalidCommand: advance_to(9); valid: 0..8"))
    c.state(state(3.0))
    assert invariants(c) == [5] and "advance_to(9)" in c.violations[0].detail and c.violations[0].time_s == 2.0


def test_a_run_an_earlier_session_left_on_the_console_is_not_this_sessions():
    c = Checker()
    c.runs_before = {13}
    c.run({"id": 13, "state": "failed", "behavior": "walk_to", "message": "stopped 37.8 cm from the goal"})
    assert invariants(c) == []
    c.run({"id": 14, "state": "failed", "behavior": "walk_to", "message": "stopped 37.8 cm from the goal"})
    assert invariants(c) == [2]
