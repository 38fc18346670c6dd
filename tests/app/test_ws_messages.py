"""The WebSocket messages keep the robot-process semantics: a stick stream during the hard e-stop is ignored
and says so; nothing streamed before the release runs after it (neither from the setpoint board nor from
the dead-man's hold); every invalid message is answered naming the field and the socket stays usable;
WS /ws/telemetry streams the state document at the rate asked for."""

from __future__ import annotations

import json
import time

import pytest
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from app.console.main import create_app
from app.console.settings import Settings
from app.service import OperatorService
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint


def _motion(client, point: str) -> list[float]:
    return client.get("/api/state").json()["operation"]["points"][point]["motion"]


# ---- the e-stop and the stick stream -----------------------------------------------------------------------
def test_a_stick_stream_during_the_estop_is_ignored_and_says_so_and_resumes_after_release(client, runtime):
    runtime.run_for(0.1)
    assert client.post("/api/estop").status_code == 200
    runtime.run_for(0.01)
    with client.websocket_connect("/ws/operator") as ws:
        for _ in range(3):
            ws.send_json({"point": "rhand", "linear": [0.05, 0, 0]})
            msg = ws.receive_json()
            assert msg["ok"] is False and msg["ignored"] is True and msg["reason"] == "hard_stop", msg
            assert "e-stop is engaged" in msg["detail"]
        assert client.post("/api/estop/release").status_code == 200
        ws.send_json({"point": "rhand", "linear": [0.05, 0, 0]})
        msg = ws.receive_json()
        assert msg["ok"] is True, msg
        runtime.run_for(0.01)  # with the stream open: its end zeroes what it moved
        assert _motion(client, "rhand")[0] == pytest.approx(0.05)


def test_a_setpoint_that_reaches_the_loop_during_the_estop_is_acknowledged_as_ignored(client, runtime):
    runtime.run_for(0.1)
    runtime.host.engage_estop()
    runtime._setpoints.put(Setpoint("rhand", (0.05, 0.0, 0.0), (0.0, 0.0, 0.0)))  # on the board, not polled yet
    runtime.run_for(0.01)
    ack = client.get("/api/state").json()["operator_acks"]["rhand"]
    assert ack["ignored"] == "hard_stop"
    assert _motion(client, "rhand") == [0.0] * 6


def test_a_setpoint_sent_before_the_release_does_not_run_after_it(client, runtime):
    runtime.run_for(0.1)
    runtime.host.engage_estop()
    runtime.run_for(0.01)
    # sent before the release, still on the board when the loop applies the release
    numbered = runtime._setpoints.put(Setpoint("lhand", (0.0, 0.05, 0.0), (0.0, 0.0, 0.0)))
    assert client.post("/api/estop/release").status_code == 200
    runtime.run_for(0.05)
    acks = client.get("/api/state").json()["operator_acks"]
    assert acks["lhand"] == {**acks["lhand"], "seq": numbered.seq, "ignored": "before_release"}
    assert _motion(client, "lhand") == [0.0] * 6
    r = client.put("/api/operator/velocity", json={"point": "lhand", "linear": [0, 0.05, 0]})
    assert r.status_code == 200, r.text  # a new one runs
    runtime.run_for(0.01)
    assert _motion(client, "lhand")[1] == pytest.approx(0.05)


def test_the_dead_man_does_not_replay_a_setpoint_held_across_a_short_estop(client, runtime):
    runtime.run_for(0.1)
    assert client.put("/api/operator/velocity", json={"point": "rhand", "linear": [0.05, 0, 0]}).status_code == 200
    runtime.run_for(0.02)
    assert _motion(client, "rhand")[0] == pytest.approx(0.05)
    client.post("/api/estop")
    runtime.run_for(0.02)
    assert client.post("/api/estop/release").status_code == 200
    runtime.run_for(0.02)  # well inside the 200 ms dead-man timeout of the setpoint
    assert _motion(client, "rhand") == [0.0] * 6


def test_a_put_during_the_estop_is_409_naming_the_stop(client, runtime):
    runtime.run_for(0.05)
    client.post("/api/estop")
    runtime.run_for(0.01)
    r = client.put("/api/operator/velocity", json={"point": "head", "angular": [0, 0, 5]})
    assert r.status_code == 409 and r.json()["reason"] == "hard_stop"


# ---- validation: the socket stays usable ---------------------------------------------------------------------
@pytest.mark.parametrize(("message", "field", "words"), [
    ("{not json", "body", "Invalid JSON"),
    ('{"point": "rhand", "linear": [0.9, 0, 0]}', "rhand.linear.0", "less than or equal to 0.5"),
    ('{"point": "rhand", "speed": 1}', "rhand.speed", "Extra inputs"),
    ('{"point": "head", "linear": [0.1, 0, 0]}', "head.linear.0", "less than or equal to 0"),
    ('{"point": "walk", "linear": [0.1, 0, 0], "max_stride": 0.4}', "walk.max_stride", "less than or equal to 0.3"),
    ("[1, 2]", "body", ""),
    (b"\x00\x01", "body", "JSON text message"),
    ("x" * 5000, "body", "the limit is 4096"),
])
def test_invalid_operator_messages_name_the_field_and_the_socket_stays_usable(client, runtime, message, field,
                                                                               words):
    runtime.run_for(0.05)
    with client.websocket_connect("/ws/operator") as ws:
        for _ in range(2):
            if isinstance(message, bytes):
                ws.send_bytes(message)
            else:
                ws.send_text(message)
            err = ws.receive_json()
            assert err["ok"] is False and err["field"] == field and words in err["detail"], err
        ws.send_json({"point": "rhand", "linear": [0.01, 0, 0]})
        assert ws.receive_json()["ok"] is True


def test_an_invalid_client_id_on_a_websocket_is_named_and_the_socket_closed(client):
    for path in ("/ws/operator?client=a%20b", "/ws/telemetry?client=a%20b"):
        with client.websocket_connect(path) as ws:
            err = ws.receive_json()
            assert err["ok"] is False and err["field"] == "client" and "not a client id" in err["detail"]
            with pytest.raises(WebSocketDisconnect) as caught:
                ws.receive_text()
            assert caught.value.code == 1008


# ---- telemetry ---------------------------------------------------------------------------------------------------
def test_telemetry_streams_the_state_document_and_takes_a_new_rate(client, runtime):
    runtime.run_for(0.05)
    with client.websocket_connect("/ws/telemetry?rate_hz=50") as ws:
        doc = ws.receive_json()
        assert doc["tick"] == runtime.loop.tick_count and "emergency" in doc and doc["operator_lock"]["holder"] is None
        for message, field, words in (('{"rate_hz": 100}', "rate_hz", "outside the allowed range [1, 50] Hz"),
                                      ('{"rate_hz": "fast"}', "rate_hz", "not a number"),
                                      ('{"rate": 5}', "rate", "unknown field"),
                                      ("{}", "rate_hz", "field required"),
                                      ("nope", "body", "invalid JSON")):
            ws.send_text(message)
            err = ws.receive_json()
            assert err == {"ok": False, "field": field, "detail": err["detail"]} and words in err["detail"], err
        ws.send_text('{"rate_hz": 20}')
        assert ws.receive_json() == {"ok": True, "rate_hz": 20.0}
        tick0 = doc["tick"]
        runtime.run_for(0.01)
        # the stream sends the newest snapshot when it is due: one taken between the two ticks may come first
        ticks = [ws.receive_json()["tick"]]
        while ticks[-1] < runtime.loop.tick_count and len(ticks) < 5:
            ticks.append(ws.receive_json()["tick"])
        assert ticks[0] > tick0 and ticks == sorted(ticks) and ticks[-1] == runtime.loop.tick_count, ticks


def test_a_ping_on_the_telemetry_is_echoed_and_a_bad_one_named(client, runtime):
    """{"ping": X} -> {"pong": X}: the page's round trip on its own stream (the link indicator)."""
    runtime.run_for(0.05)
    with client.websocket_connect("/ws/telemetry?rate_hz=1") as ws:
        ws.receive_json()
        ws.send_text('{"ping": 1234.5}')
        assert ws.receive_json() == {"pong": 1234.5}
        big = "1" + "0" * 400  # an int too large for a float, in either field
        for message, field, words in (('{"ping": "now"}', "ping", "give a finite number"),
                                      ('{"ping": true}', "ping", "give a finite number"),
                                      ('{"ping": 1e999}', "ping", "give a finite number"),
                                      ('{"ping": ' + big + '}', "ping", "give a finite number"),
                                      ('{"rate_hz": ' + big + '}', "rate_hz", "outside the allowed range"),
                                      ('{"ping": 1, "rate_hz": 5}', "body", "one field"),
                                      ('{"pong": 1}', "pong", "the fields are rate_hz and ping")):
            ws.send_text(message)
            err = ws.receive_json()
            assert err == {"ok": False, "field": field, "detail": err["detail"]} and words in err["detail"], err
        ws.send_text('{"ping": -7}')
        assert ws.receive_json() == {"pong": -7}  # the stream goes on


@pytest.mark.parametrize(("query", "words"), [("rate_hz=0", "outside the allowed range [1, 50] Hz"),
                                              ("rate_hz=51", "outside the allowed range"),
                                              ("rate_hz=nan", "not a number"), ("rate_hz=x", "not a number")])
def test_a_telemetry_rate_out_of_range_is_named_and_the_socket_closed(client, query, words):
    with client.websocket_connect(f"/ws/telemetry?{query}") as ws:
        err = ws.receive_json()
        assert err["field"] == "rate_hz" and words in err["detail"], err
        with pytest.raises(WebSocketDisconnect) as caught:
            ws.receive_text()
        assert caught.value.code == 1008


def test_telemetry_never_sends_faster_than_asked():
    robot = LocalRobot(speed=1.0)
    robot.start()
    try:
        app = create_app(Settings(extra_hosts=("testserver",)), service=OperatorService(robot))
        with TestClient(app) as client, client.websocket_connect("/ws/telemetry?rate_hz=5") as ws:
            ws.receive_json()
            t0 = time.monotonic()
            ticks = [json.loads(ws.receive_text())["tick"] for _ in range(5)]
            elapsed = time.monotonic() - t0
        assert elapsed >= 5 * 0.2 - 0.05  # 5 documents at 5 Hz: at least ~1 s (bound: 50 ms of timer slack)
        assert ticks == sorted(set(ticks))  # each a new snapshot
    finally:
        robot.stop()


def test_an_estop_message_on_the_stick_stream_engages_the_hard_stop_even_under_anothers_lock(client, runtime):
    runtime.run_for(0.1)
    assert client.post("/api/operator/lock", json={"client": "holder"}).status_code == 200
    with client.websocket_connect("/ws/operator?client=watcher") as ws:
        ws.send_json({"point": "rhand", "linear": [0.05, 0, 0]})
        assert ws.receive_json()["reason"] == "locked"  # a watcher's stick is refused...
        tick = runtime.loop.tick_count
        ws.send_text('{"estop": true}')
        reply = ws.receive_json()  # ... its e-stop never
        assert reply["ok"] and reply["estop"] and reply["message"] == "hard e-stop engaged", reply
        assert reply["tick"] >= tick and reply["engaged_at_monotonic_s"] > 0
        ws.send_text('{"estop": true}')
        assert ws.receive_json()["message"] == "hard e-stop already engaged"
        ws.send_text('{"estop": false}')  # not the e-stop message: a setpoint's validation answers it
        assert ws.receive_json()["ok"] is False
    runtime.run_for(0.01)
    assert client.get("/api/state").json()["emergency"]["hard_stop"]


def test_a_press_sent_three_ways_engages_once_and_its_late_copies_do_not_engage_after_a_release(client, runtime):
    """The page sends each E-STOP press on its door, its stick stream and as a POST, with one id: the first copy
    engages; a copy that arrives after a quick release (within the copy window) is that press again: it engages
    nothing and is not answered ok."""
    runtime.run_for(0.1)
    first = client.post("/api/estop", headers={"X-Estop-Press": "page-1:1"})
    assert first.status_code == 200 and first.json()["message"] == "hard e-stop engaged"
    assert client.post("/api/estop/release").status_code == 200
    runtime.run_for(0.01)
    late = client.post("/api/estop", headers={"X-Estop-Press": "page-1:1"})  # the POST copy, late
    assert late.status_code == 409 and late.json()["late_copy"] is True and not late.json()["ok"], late.text
    with client.websocket_connect("/ws/operator") as ws:
        ws.send_text('{"estop": true, "press": "page-1:1"}')  # the stream's copy, later still
        reply = ws.receive_json()
        assert not reply["ok"] and reply["estop"] and reply["reason"] == "late_copy", reply
        runtime.run_for(0.01)
        assert not client.get("/api/state").json()["emergency"]["hard_stop"]
        ws.send_text('{"estop": true, "press": "page-1:2"}')  # the next press: a new id, engages
        assert ws.receive_json()["message"] == "hard e-stop engaged"
    runtime.run_for(0.01)
    assert client.get("/api/state").json()["emergency"]["hard_stop"]


@pytest.mark.parametrize("press", ["", "x" * 65, "a b", "a/b", "p;q"])
def test_a_bad_press_id_on_the_post_engages_all_the_same_and_says_it_was_ignored(client, runtime, press):
    runtime.run_for(0.05)
    r = client.post("/api/estop", headers={"X-Estop-Press": press})
    assert r.status_code == 200 and r.json()["ok"], r.text
    assert "1 to 64 characters" in r.json()["press_ignored"]
    runtime.run_for(0.01)
    assert client.get("/api/state").json()["emergency"]["hard_stop"]
