"""/api/sessions: start (the simulation is reset: a session starts fresh), stop, list, download; names are
checked strictly (422 naming the field), a second start or a stop without a recording is a 409."""

import io

import pytest
from fastapi.testclient import TestClient

from app.console.main import create_app
from app.console.settings import Settings
from app.session.reader import read_stream
from app.session.replay import replay

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


@pytest.fixture
def client(service, tmp_path):
    app = create_app(Settings(extra_hosts=("testserver",), sessions_dir=str(tmp_path / "sessions")), service=service)
    with TestClient(app, headers={"content-type": "application/json"}) as c:
        yield c


def test_a_session_is_started_fresh_recorded_stopped_listed_and_downloaded(client, runtime):
    runtime.loop.run_for(0.1)
    r = client.post("/api/sessions/start", json={"name": "walk-test"})
    assert r.status_code == 200, r.text
    assert r.json()["recording"]["name"] == "walk-test.mcap" and r.json()["recording"]["ticks"] == 0
    assert runtime.loop.tick_count == 0 and runtime.host.generation == 1  # reset: it starts fresh
    assert client.post("/api/sessions/start", json={}).status_code == 409
    runtime.loop.run_for(0.2)  # 40 ticks
    assert client.post("/api/walk/go-pos", json={"x": 0.1, "y": 0.0, "theta_deg": 0.0}).status_code in (200, 409)
    runtime.loop.run_for(0.1)
    assert client.get("/api/sessions").json()["recording"]["ticks"] == 60
    r = client.post("/api/sessions/stop")
    assert r.status_code == 200 and r.json()["recording"]["finished"] and r.json()["recording"]["error"] is None
    assert client.post("/api/sessions/stop").json()["reason"] == "state"
    listed = client.get("/api/sessions").json()
    assert listed["recording"] is None and [s["name"] for s in listed["sessions"]] == ["walk-test.mcap"]
    r = client.get("/api/sessions/walk-test.mcap")
    assert r.status_code == 200 and r.headers["content-type"] == "application/octet-stream"
    session = read_stream(io.BytesIO(r.content))
    assert session.complete and session.ticks == 60 and session.header["start"] == "reset"
    assert [d["name"] for d in session.inputs] == ["go_pos"]
    assert session.inputs[0]["tick"] == 40
    assert replay(session).identical  # from a fresh robot, though this one had ticked and been reset before


def test_a_session_started_after_behaviour_runs_replays_with_their_ids(client, runtime):
    runtime.loop.run_for(0.05)  # the operation layer has ticked: behaviours may start
    assert client.post("/api/behaviors/stand", json={"time_s": 0.5}).json()["id"] == 1
    runtime.loop.run_for(0.2)
    assert client.post("/api/sessions/start", json={}).status_code == 200
    runtime.loop.run_for(0.05)
    assert client.post("/api/behaviors/stand", json={"time_s": 0.5}).json()["id"] == 2
    runtime.loop.run_for(0.05)
    assert client.post("/api/behaviors/runs/2/cancel").status_code == 200
    runtime.loop.run_for(0.05)
    name = client.post("/api/sessions/stop").json()["recording"]["name"]
    session = read_stream(io.BytesIO(client.get(f"/api/sessions/{name}").content))
    assert session.header["next_run_id"] == 2 and [d["name"] for d in session.inputs] == ["run_behavior", "cancel_run"]
    result = replay(session)
    assert result.identical, result.summary()


@pytest.mark.parametrize("name", ["../x", "a/b", ".hidden", "..", "", "x" * 70, "x" * 60, "sp ace"])
def test_a_session_name_that_is_not_a_plain_file_name_is_a_422_naming_the_field(client, name):
    r = client.post("/api/sessions/start", json={"name": name})
    assert r.status_code == 422 and r.json()["field"] == "name", r.text


def test_an_unknown_session_is_a_404_listing_the_recorded_ones_and_a_bad_one_a_422(client):
    r = client.get("/api/sessions/nothing.mcap")
    assert r.status_code == 404 and "recorded: none yet" in r.json()["detail"]
    r = client.get("/api/sessions/..%2Fsecret")
    assert r.status_code in (404, 422)
    assert client.post("/api/sessions/start", json={"name": 3}).status_code == 422
    assert client.post("/api/sessions/start", json={"nom": "x"}).status_code == 422


def test_the_start_and_stop_paths_are_not_session_names(client):
    """/api/sessions/start is that path, not a session called 'start': it has POST only (Allow says so)."""
    r = client.get("/api/sessions/start")
    assert r.status_code == 405 and r.headers["allow"] == "POST", r.text
    assert client.options("/api/sessions/stop").headers["allow"] == "POST"


def test_a_session_start_removes_the_oldest_files_beyond_the_retention_rule_never_the_one_recording(service, runtime,
                                                                                                     tmp_path):
    import os

    folder = tmp_path / "sessions"
    folder.mkdir()
    for i in range(3):
        (folder / f"old-{i}.mcap").write_bytes(b"x" * 100)
        os.utime(folder / f"old-{i}.mcap", (1_700_000_000 + i, 1_700_000_000 + i))
    settings = Settings(extra_hosts=("testserver",), sessions_dir=str(folder), sessions_keep=2)
    with TestClient(create_app(settings, service=service), headers={"content-type": "application/json"}) as client:
        r = client.post("/api/sessions/start", json={"name": "new"})
        assert r.status_code == 200, r.text
        assert r.json()["removed"] == ["old-0.mcap", "old-1.mcap"]  # 4 files with the new one: the 2 oldest go
        runtime.loop.run_for(0.05)
        assert client.post("/api/sessions/stop").status_code == 200
        assert [s["name"] for s in client.get("/api/sessions").json()["sessions"]] == ["new.mcap", "old-2.mcap"]
