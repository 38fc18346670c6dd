"""Schemathesis on the operator and behaviour routes (OpenAPI-driven fuzzing): every answer is one the
schema documents, schema-valid requests are accepted (or refused with a documented 409), nothing is a 500."""

from __future__ import annotations

import os

import pytest
import schemathesis
from hypothesis import HealthCheck, settings

from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.local import LocalRobot

pytestmark = [pytest.mark.slow, pytest.mark.in_process]  # in_process, but serial: see tests/conftest.py
EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "25"))  # per operation (a longer run: FUZZ_EXAMPLES=300)

_robot = LocalRobot(speed=None)
_robot.run_for(0.05)
APP = create_app(Settings(extra_hosts=("testserver",), lock_lease_s=0.2, lock_grace_s=0.1),
                 service=OperatorService(_robot))
schema = schemathesis.openapi.from_asgi("/openapi.json", APP).include(path_regex=r"^/api/(operator|behaviors)")


@schema.parametrize()
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
def test_the_operator_and_behaviour_routes_answer_as_documented(case):
    # (the front answers a control request that is not JSON with 415 before it looks at the method)
    headers = {"content-type": "application/json"}
    response = case.call(headers=headers)
    # while an earlier call's client holds the operator lock (its 0.2 s lease outlives a call on a slow machine) any
    # request, valid or not, is a documented 423: the lock is checked before the body, as access before validation
    excluded = ([schemathesis.checks.positive_data_acceptance, schemathesis.checks.negative_data_rejection]
                if response.status_code == 423 else [])
    case.validate_response(response, excluded_checks=excluded, headers=headers)
