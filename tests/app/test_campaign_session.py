"""A session whose console stops answering the state document ends as a finding (invariant 5), not as a crash
of the whole campaign (a CI run under load: `KeyError: 'time'` took every other session with it)."""

from __future__ import annotations

import pytest

from app.lab.campaign.session import Session, StateUnavailable


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
