"""The operator API: PUT /api/operator/velocity and the /ws/operator stream reach the operation layer through
the latest-value channel, stamped with the control time and acknowledged with the tick they reached; the
dead-man lets go of a setpoint not renewed; the validation and refusals; the operation layer's parameters."""

from __future__ import annotations

import math

import pytest
from starlette.websockets import WebSocketDisconnect


def _status(client, point: str) -> dict:
    return client.get("/api/state").json()["operation"]["points"][point]


def test_a_put_setpoint_reaches_the_op_layer_at_the_next_tick_and_the_dead_man_lets_it_go(client, runtime):
    runtime.run_for(0.5)
    tick = runtime.loop.tick_count
    r = client.put("/api/operator/velocity", json={"point": "rhand", "linear": [0.05, 0, 0]})
    assert r.status_code == 200, r.text
    ack = r.json()
    assert ack["tick"] == tick and ack["time_s"] == pytest.approx(0.5) and ack["seq"] == ack["applied_seq"]
    runtime.run_for(0.1)
    motion = _status(client, "rhand")["motion"]
    assert motion[0] == pytest.approx(0.05)
    runtime.run_for(0.4)  # older than 200 ms, ramped down over 100 ms: zero
    assert _status(client, "rhand")["motion"] == [0.0] * 6
    state = client.get("/api/state").json()
    assert state["operator_acks"]["rhand"]["seq"] == ack["seq"]


def test_angular_rates_are_in_degrees_per_second_and_walk_takes_the_step_parameters(client, runtime):
    runtime.run_for(0.1)
    r = client.put("/api/operator/velocity", json={"point": "head", "angular": [0, 0, 10.0]})
    assert r.status_code == 200, r.text
    runtime.run_for(0.05)
    assert _status(client, "head")["motion"][5] == pytest.approx(math.radians(10.0))
    r = client.put("/api/operator/velocity", json={"point": "walk", "linear": [0.1, 0, 0], "angular": [0, 0, 5],
                                                   "max_stride": 0.2, "foot_distance": 0.2})
    assert r.status_code == 200, r.text


@pytest.mark.parametrize(("body", "field", "words"), [
    ({"point": "head", "linear": [0.1, 0, 0]}, "head.linear.0", "less than or equal to 0"),
    ({"point": "walk", "linear": [0, 0, 0.1]}, "walk.linear.2", "less than or equal to 0"),
    ({"point": "rhand", "linear": [0.9, 0, 0]}, "rhand.linear.0", "less than or equal to 0.5"),
    ({"point": "rhand", "max_stride": 0.2}, "rhand.max_stride", "unknown field"),
    ({"point": "tail"}, "body", "'rhand', 'lhand', 'head', 'waist', 'walk'"),
    ({"point": "rhand", "linear": [0, 0]}, "rhand.linear.2", "field required"),
    ({"point": "rhand", "linear": ["0.1", 0, 0]}, "rhand.linear.0", "valid number"),
])
def test_invalid_setpoints_are_422_naming_the_field(client, body, field, words):
    r = client.put("/api/operator/velocity", json=body)
    assert r.status_code == 422, r.text
    assert r.json()["field"] == field and words in r.json()["detail"], r.json()


def test_setpoints_are_refused_under_the_hard_estop(client, runtime):
    runtime.run_for(0.05)
    assert client.post("/api/estop").status_code == 200
    runtime.run_for(0.05)
    r = client.put("/api/operator/velocity", json={"point": "rhand", "linear": [0.05, 0, 0]})
    assert r.status_code == 409 and r.json()["reason"] == "hard_stop"


def test_the_stream_acknowledges_each_setpoint_with_the_tick_it_reached(client, runtime):
    runtime.run_for(0.1)
    with client.websocket_connect("/ws/operator") as ws:
        seen = []
        for _ in range(5):
            tick = runtime.loop.tick_count
            ws.send_json({"point": "lhand", "linear": [0, 0.02, 0]})
            ack = ws.receive_json()
            assert ack["ok"] and ack["point"] == "lhand" and ack["tick"] == tick, ack
            seen.append(ack["seq"])
            runtime.run_for(0.02)  # 50 Hz
        assert seen == sorted(seen) and len(set(seen)) == 5
        ws.send_json({"point": "lhand", "linear": [0, 2.0, 0]})
        err = ws.receive_json()
        assert err["ok"] is False and err["field"] == "lhand.linear.1"
        ws.send_text("not json")
        assert ws.receive_json()["ok"] is False
    assert _status(client, "lhand")["motion"][1] == pytest.approx(0.02)


def test_a_stream_that_ends_stops_what_it_moved_at_the_next_tick(client, runtime):
    # without it the dead-man would let go after 200 ms and a 100 ms ramp (issue 12: zero within 250 ms)
    runtime.run_for(0.1)
    with client.websocket_connect("/ws/operator") as ws:
        for _ in range(5):
            ws.send_json({"point": "rhand", "linear": [0.05, 0, 0]})
            assert ws.receive_json()["ok"]
            runtime.run_for(0.02)
        assert _status(client, "rhand")["motion"][0] == pytest.approx(0.05)
    client.get("/api/health")  # the close has been handled by the server
    runtime.run_for(0.01)  # two ticks: the zero reached the operation layer at the first
    assert _status(client, "rhand")["motion"] == [0.0] * 6


def test_the_stream_is_refused_to_pages_of_another_origin(client):
    with pytest.raises(WebSocketDisconnect) as err:
        with client.websocket_connect("/ws/operator", headers={"origin": "http://evil.example"}) as ws:
            ws.receive_json()
    assert err.value.code == 1008


def test_operation_parameters_are_read_and_replaced_with_named_errors(client):
    doc = client.get("/api/operator/params").json()
    assert doc["params"]["deadman_timeout_s"] == 0.2
    assert any(f["name"] == "hand_speed_m_s" and f["unit"] == "m/s" for f in doc["schema"])
    r = client.put("/api/operator/params", json={"hand_speed_m_s": 0.2})
    assert r.status_code == 200 and r.json()["params"]["hand_speed_m_s"] == 0.2
    r = client.put("/api/operator/params", json={"hand_speed_m_s": 5.0})
    assert r.status_code == 422 and r.json()["field"] == "hand_speed_m_s"
