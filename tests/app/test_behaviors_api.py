"""The behaviour API: the list generated from each behaviour's Params, starting a run, its state in
/api/behaviors/runs/{id} and /api/state, cancelling, and the errors (404 with the valid names, 422 naming
the field, 409 naming the run that holds the point)."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def _step(runtime, seconds: float) -> None:
    runtime.run_for(seconds)


def test_the_list_gives_every_behaviour_with_its_parameters_types_units_and_ranges(client):
    r = client.get("/api/behaviors")
    assert r.status_code == 200
    by_name = {b["name"]: b for b in r.json()}
    assert sorted(by_name) == ["approach_table", "follow_arc", "grasp", "locate_can", "locate_handle", "locate_trash",
                               "locate_trash_box", "look_at", "open_door", "reach", "recognise", "release", "sequence",
                               "squat", "stand", "take_can", "throw_can", "walk_to"]
    force = next(p for p in by_name["grasp"]["params"] if p["name"] == "force_n")
    assert force == {"name": "force_n", "type": "number", "default": 10.0, "unit": "N", "min": 1.0, "max": 14.0,
                     "choices": None, "doc": "fingertip force to hold with (JRL-hand: 14 N at most)", "place": None}
    hand = next(p for p in by_name["reach"]["params"] if p["name"] == "hand")
    assert hand["choices"] == ["rhand", "lhand"] and hand["type"] == "string"


def test_a_run_starts_reports_progress_and_ends_in_the_run_and_state_documents(client, runtime):
    r = client.post("/api/behaviors/release", json={"time_s": 0.5})
    assert r.status_code == 200, r.text
    run_id = r.json()["id"]
    _step(runtime, 0.25)
    run = client.get(f"/api/behaviors/runs/{run_id}").json()
    assert run["state"] == "running" and 0.0 < run["progress"] < 1.0 and run["points"] == ["rhand.gripper"]
    _step(runtime, 1.0)
    run = client.get(f"/api/behaviors/runs/{run_id}").json()
    assert run["state"] == "succeeded" and run["progress"] == 1.0 and run["message"] == "gripper open"
    state = client.get("/api/state").json()
    assert [s["id"] for s in state["runs"]] == [run_id] and state["runs"][0]["state"] == "succeeded"
    assert client.get("/api/behaviors/runs").json()[0]["id"] == run_id


def test_a_second_run_on_the_same_gripper_is_refused_naming_the_first_and_cancel_frees_it(client, runtime):
    first = client.post("/api/behaviors/release", json={"time_s": 2.0}).json()["id"]
    r = client.post("/api/behaviors/grasp", json={})
    assert r.status_code == 409 and r.json()["reason"] == "state"
    assert f"run {first} (release)" in r.json()["detail"]
    r = client.post(f"/api/behaviors/runs/{first}/cancel")
    assert r.status_code == 200 and r.json()["state"] == "cancelled"
    assert client.post("/api/behaviors/grasp", json={"require_object": False}).status_code == 200


def test_an_omitted_body_runs_with_the_defaults(client):
    r = client.post("/api/behaviors/release")
    assert r.status_code == 200, r.text


def test_unknown_names_are_404_with_the_valid_ones(client):
    r = client.post("/api/behaviors/dance", json={})
    assert r.status_code == 404 and ("valid: approach_table, follow_arc, grasp, locate_can, locate_handle, "
                                     "locate_trash, locate_trash_box, look_at, open_door, reach, recognise, release, "
                                     "sequence, squat, stand, take_can, throw_can, walk_to") in \
        r.json()["detail"]
    r = client.get("/api/behaviors/runs/77")
    assert r.status_code == 404 and "no run 77" in r.json()["detail"]


def test_bad_parameters_are_422_naming_the_field(client):
    r = client.post("/api/behaviors/grasp", json={"force_n": 20.0})
    assert r.status_code == 422 and r.json()["field"] == "force_n" and "14" in r.json()["detail"]
    r = client.post("/api/behaviors/reach", json={"hand": "head"})
    assert r.status_code == 422 and r.json()["field"] == "hand"
    r = client.post("/api/behaviors/squat", json={"depth": 0.1})
    assert r.status_code == 422 and r.json()["field"] == "depth"
    r = client.post("/api/behaviors/sequence", json={"steps": [{"behavior": "squat", "params": {"depth_m": 9}}]})
    assert r.status_code == 422 and r.json()["field"].endswith("params.depth_m"), r.json()
    r = client.post("/api/behaviors/sequence", json={"steps": []})
    assert r.status_code == 422 and r.json()["field"] == "steps"


def test_a_sequence_runs_its_steps(client, runtime):
    steps = [{"behavior": "release", "params": {"time_s": 0.3}},
             {"behavior": "grasp", "params": {"time_s": 0.3, "require_object": False}}]
    run_id = client.post("/api/behaviors/sequence", json={"steps": steps}).json()["id"]
    _step(runtime, 3.0)
    run = client.get(f"/api/behaviors/runs/{run_id}").json()
    assert run["state"] == "succeeded", run
    assert run["result"]["0.release"]["message"] == "gripper open"
    assert run["result"]["1.grasp"]["holding"] is False


def test_behaviour_routes_are_refused_from_another_origin(client):
    r = client.post("/api/behaviors/release", json={}, headers={"origin": "http://evil.example"})
    assert r.status_code == 403


def test_the_hard_estop_cancels_a_running_behaviour_and_nothing_resumes_on_release(runtime, service):
    runtime.run_for(2.5)  # the AutoBalancer running
    run_id = service.run_behavior("squat", {"depth_m": 0.15})
    runtime.run_for(0.8)
    assert service.get_run(run_id).state == "running"
    service.estop()
    runtime.run_for(0.1)
    run = service.get_run(run_id)
    assert run.state == "cancelled" and "e-stop" in run.message
    service.release_estop()
    runtime.run_for(1.0)
    op = runtime.loop.chain.layers["op"]
    z0_m = op.view().waist_height_m
    runtime.run_for(2.0)
    assert service.get_run(run_id).state == "cancelled"
    assert not runtime.host.observation.fallen and runtime.loop.fault is None
    assert abs(op.view().waist_height_m - z0_m) < 1e-3  # the squat did not go on after the release


def test_an_integer_parameter_takes_an_integral_number_and_nothing_else(client):
    """JSON Schema's "integer" includes 2.0 (schemathesis sends it); 2.5, true and "2" stay refused."""
    for bad in (2.5, True, "2"):
        r = client.post("/api/behaviors/locate_can", json={"views": bad})
        assert r.status_code == 422 and r.json()["field"] == "views", (bad, r.json())
    r = client.post("/api/behaviors/locate_can", json={"views": 2.0})
    # past validation: refused only for the robot's state (this client's chain has not ticked the operation layer)
    assert r.status_code == 409 and r.json()["reason"] == "state", r.json()
