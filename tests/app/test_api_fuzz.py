"""Schemathesis over the whole OpenAPI document while the control loop runs at real time in its thread:
every answer is one the schema documents (status, content type, body), nothing is a 5xx, at least 1000
calls; afterwards the loop still ticks and, once reset, the robot stands."""

from __future__ import annotations

import os
import time

import pytest
import schemathesis
from hypothesis import HealthCheck, settings

from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.local import LocalRobot

pytestmark = pytest.mark.slow
# per operation (schemathesis's coverage phase adds its boundary cases: 3 gave 4677 calls over 61 operations)
EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "3"))
MIN_CALLS = int(os.environ.get("FUZZ_MIN_CALLS", "1000"))
STANDING_Z_M = (0.55, 0.75)  # [m] BODY height of the standing robot (home pose: 0.648 m)

_robot = LocalRobot(speed=1.0)
_robot.start()
# a short lease: a lock the fuzzer takes with some client id is gone before long, the other calls go on
APP = create_app(Settings(extra_hosts=("testserver",), lock_lease_s=0.2, lock_grace_s=0.1),
                 service=OperatorService(_robot))
schema = schemathesis.openapi.from_asgi("/openapi.json", APP)
CALLS = {"n": 0, "by_status": {}}


@schema.parametrize()
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
def test_every_route_answers_as_documented(case):
    # (the front answers a control request that is not JSON with 415 before it looks at the method)
    headers = {"content-type": "application/json"}
    response = case.call(headers=headers)
    # a valid request while an earlier call's client holds the operator lock is a documented 423 ("not you,
    # not now", as a 409 is "not now"), and an invalid one meeting the lock is refused by it before its body
    # is read (nothing reaches the robot either way): every other check still applies to it
    excluded = ([schemathesis.checks.positive_data_acceptance, schemathesis.checks.negative_data_rejection]
                if response.status_code == 423 else [])
    case.validate_response(response, excluded_checks=excluded, headers=headers)
    CALLS["n"] += 1
    CALLS["by_status"][response.status_code] = CALLS["by_status"].get(response.status_code, 0) + 1


def test_after_the_fuzz_the_loop_ticks_and_the_robot_stands_once_reset():
    from fastapi.testclient import TestClient

    print(f"fuzz calls: {CALLS['n']}, by status: {dict(sorted(CALLS['by_status'].items()))}")
    assert CALLS["n"] >= MIN_CALLS, CALLS
    assert not any(code >= 500 for code in CALLS["by_status"]), CALLS
    assert _robot.running
    t0 = _robot.loop.tick_count
    time.sleep(0.3)
    assert _robot.loop.tick_count > t0 + 20  # 60 ticks at real time; 20 leaves room for a loaded machine
    with TestClient(APP, headers={"content-type": "application/json"}) as client:
        before = client.get("/api/state").json()
        print(f"after the fuzz: fallen {before['fallen']}, hard stop {before['emergency']['hard_stop']}, "
              f"BODY z {before['base']['pos'][2]:.3f} m")
        assert client.post("/api/sim/reset").status_code == 200
        time.sleep(2.0)
        state = client.get("/api/state").json()
    assert state["time"] > 1.0 and not state["fallen"] and not state["emergency"]["hard_stop"]
    assert STANDING_Z_M[0] < state["base"]["pos"][2] < STANDING_Z_M[1], state["base"]
    _robot.stop()
