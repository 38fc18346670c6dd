"""A session whose console stops answering the state document ends as a finding (invariant 5), not as a crash
of the whole campaign (a CI run under load: `KeyError: 'time'` took every other session with it)."""

from __future__ import annotations

import math

import pytest

from app.lab.campaign.grammar import Action
from app.lab.campaign.session import Session, StateUnavailable

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


@pytest.mark.parametrize("status, body", [(503, {"detail": "the robot process is not running"}),
                                          (200, {"detail": "not a state document"}), (502, "Bad Gateway")])
def test_a_session_without_the_state_ends_with_an_invariant_5_finding(monkeypatch, status, body):
    def request(self, method, path, body_=None, headers=None, check=True):
        if (method, path) == ("GET", "/api/state"):
            if check:
                self.checker.answer(f"{method} {path}", status, body)
            return status, body
        return 200, []

    monkeypatch.setattr(Session, "request", request)
    session = Session(port=9, seed=1, seconds=1.0, catalogue={}, actions=[])
    result = session.run()
    assert [v.invariant for v in result.violations][-1] == 5
    assert f"GET /api/state answered {status}" in result.violations[-1].detail


def test_the_state_unavailable_names_the_answer():
    assert "answered 503: {'detail': 'x'}" in str(StateUnavailable(503, {"detail": "x"}))


def test_the_old_simulations_states_after_a_reset_are_not_the_new_robots(monkeypatch):
    # soak seed 10618: a robot fallen before the reset (after a push beyond the envelope) was still in the state
    # documents read while the reset took effect, and counted as the new robot's fall without a push (invariant 1)
    fallen = {"time": 59.5, "tick": 11900, "fallen": True}
    states = iter([fallen, {**fallen, "time": 59.56, "tick": 11912}, {"time": 0.01, "tick": 2, "fallen": False},
                   {"time": 2.6, "tick": 520, "fallen": False}])

    def request(self, method, path, body_=None, headers=None, check=True):
        return (200, next(states)) if (method, path) == ("GET", "/api/state") else (200, {})

    monkeypatch.setattr(Session, "request", request)
    session = Session(port=9, seed=1, seconds=1.0, catalogue={}, actions=[])
    session.checker.push(42.0, 20.0)  # beyond the envelope: the fall before the reset is no violation
    session.reset_and_warm_up()
    assert session.checker.violations == [] and session.checker.falls == [{"time_s": 59.5,
                                                                            "pushes": [(0.0, 42.0, 20.0)]}]


def test_a_push_just_after_a_walk_was_accepted_is_drawn_from_and_held_to_the_walking_envelope(monkeypatch):
    # soak seed 11023: goVelocity accepted, then at once an 18 N s push drawn from the standing envelope (the state
    # read did not show the walk yet); the robot, in its first step, fell, and the fall counted as within the envelope
    sent = []

    def request(self, method, path, body_=None, headers=None, check=True):
        sent.append((method, path, body_))
        return 200, {"ok": True}

    monkeypatch.setattr(Session, "request", request)
    session = Session(port=9, seed=1, seconds=1.0, catalogue={}, actions=[])
    session.state = {"walking": False, "emergency": {"hard_stop": False}, "layers": {}}
    push = Action(0.0, "push", {"envelope_fraction": 0.9, "direction_deg": 85.4})
    session.act(push)  # standing: 18 N s of a 20 N s envelope
    session.act(Action(0.0, "go_velocity", {"vx": -0.0248, "vy": -0.1044, "vtheta_deg": -14.63}))
    session.act(push)  # the walk accepted, not yet in the state: 9 N s of the walking 10 N s
    forces = [math.hypot(*body["force"][:2]) * body["duration"] for _, path, body in sent if path == "/api/sim/push"]
    assert forces == pytest.approx([18.0, 9.0], abs=1e-3)  # the force is sent rounded to the mN
    assert [(round(j, 3), e) for _, j, e in session.checker.pushes] == [(18.0, 20.0), (9.0, 10.0)]


def test_a_request_the_console_does_not_answer_in_time_ends_the_session_with_an_invariant_5_finding():
    # a soak piece crashed whole (TimeoutError out of GET /api/state) instead of ending the one session with a finding
    class Silent:
        timeout = 30.0

        def request(self, *a, **k):
            pass

        def getresponse(self):
            raise TimeoutError("timed out")

        def close(self):
            pass

    session = Session(port=9, seed=1, seconds=1.0, catalogue={}, actions=[])
    session.conn = Silent()
    result = session.run()
    assert [v.invariant for v in result.violations] == [5]
    assert "the console stopped answering: GET /api/" in result.violations[0].detail
    assert "no answer within 30 s" in result.violations[0].detail
