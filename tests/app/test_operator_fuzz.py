"""Schemathesis on the operator and behaviour routes (OpenAPI-driven fuzzing): every answer is one the
schema documents, schema-valid requests are accepted (or refused with a documented 409), nothing is a 500."""

from __future__ import annotations

import os

import pytest
import schemathesis
from hypothesis import HealthCheck, settings

from app.main import create_app
from app.service import OperatorService
from app.service.local import LocalRobot
from app.settings import Settings

pytestmark = pytest.mark.slow
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
    # a valid request while an earlier call's client holds the operator lock is a documented 423
    excluded = [schemathesis.checks.positive_data_acceptance] if response.status_code == 423 else []
    case.validate_response(response, excluded_checks=excluded, headers=headers)
