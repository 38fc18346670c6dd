"""The random operator's grammar: a seed gives one action list; the kinds come at their stated probabilities;
every action it draws is valid by the API's own schemas (behaviour bodies, setpoints, walks, pushes, params)."""

from __future__ import annotations

import math
from collections import Counter

import pytest

from app.console.routers.behaviors import params_model
from app.console.routers.operator import _REQUEST as VELOCITY_REQUEST
from app.console.schemas import GoPosRequest, GoVelocityRequest, PushRequest
from app.lab.campaign.grammar import (
    PROBABILITIES,
    PUSH_ENVELOPE_NS,
    SCENE_BEHAVIORS,
    Action,
    actions_for,
    catalogue_of,
    push_request,
)
from behaviors.registry import BEHAVIORS

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


@pytest.fixture(scope="module")
def catalogue():
    from app.service import OperatorService
    from app.service.local import LocalRobot

    robot = LocalRobot(speed=None)
    try:
        yield catalogue_of(OperatorService(robot).list_behaviors())
    finally:
        robot.stop()


def test_the_probabilities_sum_to_one_and_every_behaviour_drawn_exists(catalogue):
    assert math.isclose(sum(PROBABILITIES.values()), 1.0)
    assert set(SCENE_BEHAVIORS) <= set(catalogue)


def test_the_same_seed_gives_the_same_action_list_and_another_seed_another(catalogue):
    a = actions_for(7, 60.0, catalogue)
    assert a == actions_for(7, 60.0, catalogue)
    assert a != actions_for(8, 60.0, catalogue)
    assert all(0 < x.at_s < 60.0 for x in a) and [x.at_s for x in a] == sorted(x.at_s for x in a)
    assert [Action.from_dict(x.to_dict()) for x in a] == a


def test_the_kinds_come_at_their_stated_probabilities(catalogue):
    counts = Counter(a.kind for seed in range(60) for a in actions_for(seed, 120.0, catalogue))
    n = sum(counts.values())
    assert n > 3000
    for kind, p in PROBABILITIES.items():
        sigma = math.sqrt(p * (1 - p) / n)
        assert abs(counts[kind] / n - p) < 4 * sigma + 1e-3, (kind, counts[kind] / n, p)


def test_every_action_is_valid_by_the_api_schemas(client, catalogue):
    schemas = {path: {s["name"]: s for s in client.get(path).json()["schema"]}
               for path in ("/api/emergency-stopper/params", "/api/operator/params")}
    ab = client.get("/api/auto-balancer/params").json()
    kinds = Counter()
    for seed in range(40):
        for a in actions_for(seed, 60.0, catalogue):
            kinds[a.kind] += 1
            p = a.params
            if a.kind in ("stick", "closed_tab", "compete"):
                VELOCITY_REQUEST.validate_python(p["body"])
            elif a.kind == "go_velocity":
                GoVelocityRequest.model_validate(p)
            elif a.kind == "go_pos":
                GoPosRequest.model_validate(p)
            elif a.kind == "behavior":
                params_model(BEHAVIORS[p["name"]].Params, "Body").model_validate(p["params"])
            elif a.kind in ("push", "push_beyond"):
                for walking in (False, True):
                    body, impulse, envelope = push_request(a, walking)
                    PushRequest.model_validate(body)
                    assert (impulse <= envelope) is (a.kind == "push")
            elif a.kind == "params":
                if p["path"] in schemas:
                    s = schemas[p["path"]][p["field"]]
                    assert s["min"] <= p["value"] <= s["max"], a
                else:
                    assert p["field"] in ab.get("params", ab), a
    assert set(kinds) == set(PROBABILITIES)


def test_a_push_is_a_fraction_of_the_envelope_the_robot_is_in():
    a = Action(1.0, "push", {"envelope_fraction": 0.5, "direction_deg": 90.0})
    body, impulse, envelope = push_request(a, walking=True)
    assert envelope == PUSH_ENVELOPE_NS["walking"] and impulse == pytest.approx(envelope / 2)
    assert body["force"][0] == pytest.approx(0.0, abs=1e-6) and body["force"][1] == pytest.approx(impulse / 0.1)


@pytest.mark.parametrize("walking", [False, True])
def test_a_push_while_the_hard_estop_holds_the_robot_frozen_is_beyond_the_envelope(walking):
    # campaign seed 3006: frozen mid-stride by the e-stop, a 9.4 N s push (inside the walking 10) felled it; frozen,
    # nothing balances: the impulse is drawn as before, the fall invariant holds it to no envelope
    a = Action(1.0, "push", {"envelope_fraction": 0.5, "direction_deg": 90.0})
    body, impulse, envelope = push_request(a, walking=walking, frozen=True)
    drawn = PUSH_ENVELOPE_NS["walking" if walking else "standing"]
    assert impulse == pytest.approx(drawn / 2) and envelope == 0.0 and impulse > envelope
    assert push_request(a, walking=walking)[0] == body
