"""GET/PUT /api/params round trip (all or none) and `hrp2-console --params FILE` taking effect."""

import copy
import json

import pytest

from app.cli import run_parser
from app.service import OperatorService
from app.service.local import LocalRobot

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_a_document_with_one_invalid_value_is_refused_whole_naming_the_field(client):
    original = client.get("/api/params").json()
    assert {"st", "es", "abc", "ic:rarm"} <= original.keys()
    doc = copy.deepcopy(original)
    doc["st"]["cp_threshold_m"] = original["st"]["cp_threshold_m"] + 0.01  # valid
    doc["es"]["t1_s"] = -1.0  # out of range
    r = client.put("/api/params", json=doc)
    assert r.status_code == 422, r.text
    assert "es.t1_s" in r.json()["detail"]
    assert client.get("/api/params").json() == original  # not even the valid change


def test_the_document_put_back_with_a_valid_change_applies_it_and_nothing_else(client):
    original = client.get("/api/params").json()
    doc = copy.deepcopy(original)
    doc["st"]["cp_threshold_m"] = original["st"]["cp_threshold_m"] + 0.01
    r = client.put("/api/params", json=doc)
    assert r.status_code == 200, r.text
    now = client.get("/api/params").json()
    assert now["st"]["cp_threshold_m"] == doc["st"]["cp_threshold_m"]
    now["st"]["cp_threshold_m"] = original["st"]["cp_threshold_m"]
    assert now == original


def test_the_cli_params_file_is_what_the_robot_starts_with(tmp_path):
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"st": {"cp_threshold_m": 0.05}, "es": {"t1_s": 0.8}}))
    args = run_parser().parse_args(["--headless", "--params", str(path)])  # the CLI's own file loading
    robot = LocalRobot(speed=None, params=args.params)  # what the console hands its robot process
    try:
        p = OperatorService(robot).params("st", "es")
        assert (p["st"].cp_threshold_m, p["es"].t1_s) == (0.05, 0.8)
    finally:
        robot.stop()


def test_a_document_of_before_the_nested_emergency_step_loads_its_flat_names(client):
    r = client.put("/api/params", json={"abc": {"emergency_step": False, "emergency_step_time_s": 0.5,
                                                "emergency_step_height_m": 0.05}})
    assert r.status_code == 200, r.text
    es = client.get("/api/params").json()["abc"]["emergency_step"]
    assert (es["enabled"], es["step_time_s"], es["step_height_m"]) == (False, 0.5, 0.05)
    r = client.put("/api/params", json={"abc": {"emergency_step_time_s": 9.0}})
    assert r.status_code == 422 and "abc.emergency_step.step_time_s" in r.json()["detail"], r.text
