"""The console's token and operator lock: a console bound beyond loopback refuses to start without a token;
with one, every /api/ request and WebSocket needs it (missing or wrong: 401 / closed with 1008); while a
client holds the lock, the others' control requests are 423 naming the holder, the e-stop never is; the lock
goes after a grace time once the holder's last WebSocket closed; an unexpected error is a JSON 500 after which
the same keep-alive connection still carries an e-stop."""

from __future__ import annotations

import http.client
import json
import socket
import threading
import time

import pytest
import uvicorn
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from app.console.main import create_app
from app.console.operator_lock import Locked, OperatorLock
from app.console.security import TOKEN_ENV, TokenRequired, check_token_config, token_from_env
from app.console.settings import Settings
from app.service import OperatorService
from app.service.local import LocalRobot

TOKEN = "s3cret-token-of-the-console"
JSON = {"content-type": "application/json"}


@pytest.fixture(scope="module")
def robot():
    r = LocalRobot(speed=None)
    r.run_for(0.05)
    yield r
    r.stop()


@pytest.fixture(scope="module")
def service(robot):
    return OperatorService(robot)


@pytest.fixture
def secured(service):
    app = create_app(Settings(host="0.0.0.0", token=TOKEN), service=service)
    with TestClient(app, headers=JSON) as c:
        yield c


@pytest.fixture
def locked_app(service, robot):
    if robot.loop.hard_stop_engaged:
        robot.host.release_estop()
    app = create_app(Settings(extra_hosts=("testserver",), lock_lease_s=5.0, lock_grace_s=0.2), service=service)
    with TestClient(app, headers=JSON) as c:
        yield c


# ---- binding and the token ------------------------------------------------------------------------------------
@pytest.mark.parametrize("host", ["0.0.0.0", "192.168.1.20", "::"])
def test_a_console_beyond_loopback_refuses_to_start_without_a_token(host):
    with pytest.raises(TokenRequired, match="--token or the environment variable HRP2_CONSOLE_TOKEN"):
        check_token_config(host, None)
    with pytest.raises(TokenRequired):
        create_app(Settings(host=host))


def test_loopback_needs_no_token_and_a_short_token_is_refused():
    for host in ("127.0.0.1", "localhost", "::1"):
        check_token_config(host, None)
    with pytest.raises(TokenRequired, match="at least 16 printable characters"):
        check_token_config("0.0.0.0", "short")
    with pytest.raises(TokenRequired, match="without spaces"):
        check_token_config("0.0.0.0", "a token with spaces in it")


def test_the_token_comes_from_the_option_else_the_environment(monkeypatch):
    monkeypatch.setenv(TOKEN_ENV, "from-the-environment-0123")
    assert token_from_env(None) == "from-the-environment-0123"
    assert token_from_env("given-on-the-command-line") == "given-on-the-command-line"
    monkeypatch.delenv(TOKEN_ENV)
    assert token_from_env(None) is None


def test_the_cli_refuses_a_public_host_without_a_token_with_a_clear_message(capsys, monkeypatch):
    from app.cli import run

    monkeypatch.delenv(TOKEN_ENV, raising=False)
    assert run(["--host", "0.0.0.0", "--headless", "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "hrp2-console: error: --host 0.0.0.0 lets other machines reach the console" in err
    assert "--token" in err and TOKEN_ENV in err


@pytest.mark.parametrize(("headers", "status"), [
    ({}, 401),
    ({"authorization": "Bearer wrong-token-wrong-token"}, 401),
    ({"authorization": TOKEN}, 401),  # without the scheme
    ({"authorization": f"Bearer {TOKEN}"}, 200),
])
def test_http_needs_the_bearer_token_on_reads_and_control(secured, headers, status):
    r = secured.get("/api/state", headers=headers)
    assert r.status_code == status, r.text
    r = secured.post("/api/motion/stop", headers=headers)
    assert r.status_code == status, r.text
    if status == 401:
        assert r.headers["www-authenticate"] == "Bearer"
        assert "Authorization: Bearer <token>" in r.json()["detail"]
    else:
        assert secured.post("/api/motion/release", headers=headers).status_code in (200, 409)


def test_the_estop_needs_the_token_too_and_the_page_and_docs_do_not(secured):
    assert secured.post("/api/estop").status_code == 401
    r = secured.post("/api/estop", headers={"authorization": f"Bearer {TOKEN}"})
    assert r.status_code == 200 and r.json()["ok"]
    assert secured.post("/api/estop/release", headers={"authorization": f"Bearer {TOKEN}"}).status_code == 200
    for path in ("/", "/docs", "/openapi.json"):
        assert secured.get(path).status_code == 200, path


@pytest.mark.parametrize("query", ["", "?token=wrong-token-wrong-token", f"?token={TOKEN[:-1]}"])
def test_websockets_without_the_right_token_are_closed_with_1008(secured, query):
    for path in ("/ws/operator", "/ws/telemetry"):
        with pytest.raises(WebSocketDisconnect) as caught:
            with secured.websocket_connect(path + query) as ws:
                ws.receive_text()
        assert caught.value.code == 1008
        assert "token" in caught.value.reason


def test_websockets_with_the_token_are_served(secured):
    with secured.websocket_connect(f"/ws/telemetry?token={TOKEN}&rate_hz=20") as ws:
        doc = ws.receive_json()
        assert "emergency" in doc and "operator_lock" in doc
    with secured.websocket_connect(f"/ws/operator?token={TOKEN}") as ws:
        ws.send_text('{"point": "tail"}')
        assert ws.receive_json()["ok"] is False


# ---- the operator lock ----------------------------------------------------------------------------------------
def _take(app, name: str) -> str:
    """Take the lock as `name`; its lease token."""
    r = app.post("/api/operator/lock", json={"client": name})
    assert r.status_code == 200, r.text
    return r.json()["token"]


def test_the_lock_is_taken_explicitly_and_shown_to_all_without_its_token(locked_app):
    assert locked_app.get("/api/operator/lock").json()["holder"] is None
    r = locked_app.post("/api/operator/lock", json={"client": "alice"})
    assert r.status_code == 200, r.text
    token = r.json()["token"]
    assert r.json()["holder"] == "alice" and r.json()["lease_s"] == 5.0 and len(token) >= 32
    shown = locked_app.get("/api/operator/lock").json()
    assert shown["holder"] == "alice" and "token" not in shown
    state = locked_app.get("/api/state")
    assert state.json()["operator_lock"]["holder"] == "alice" and token not in state.text
    r = locked_app.post("/api/operator/lock", json={"client": "bob"})
    assert r.status_code == 423 and r.json()["holder"] == "alice" and "'alice'" in r.json()["detail"]
    r = locked_app.post("/api/operator/lock", json={"client": "alice"})  # the name is not the holder
    assert r.status_code == 423 and "token" not in r.json(), r.text
    r = locked_app.post("/api/operator/lock", json={"client": "alice"}, headers={"x-lock-token": token})
    assert r.status_code == 200 and r.json()["token"] == token  # the holder renews it with its token
    assert token not in locked_app.get("/api/state").text  # nor does the journal show it
    locked_app.delete("/api/operator/lock", headers={"x-lock-token": token})


def test_control_requests_of_others_are_423_naming_the_holder_and_the_estop_always_passes(locked_app, robot):
    token = _take(locked_app, "alice")
    for headers in ({}, {"x-client-id": "bob"}, {"x-client-id": "alice"}, {"x-lock-token": "guessed"}):
        r = locked_app.post("/api/walk/go-pos", json={"x": 0.0, "y": 0.0, "theta_deg": 0.0}, headers=headers)
        assert r.status_code == 423, r.text
        assert r.json() == {"detail": r.json()["detail"], "reason": "locked", "holder": "alice"}
        assert "POST /api/walk/go-pos refused" in r.json()["detail"] and "X-Lock-Token" in r.json()["detail"]
        assert locked_app.put("/api/operator/velocity", json={"point": "rhand"}, headers=headers).status_code == 423
        assert locked_app.post("/api/sim/reset", headers=headers).status_code == 423
    assert locked_app.get("/api/state", headers={"x-client-id": "bob"}).status_code == 200  # watching is free
    r = locked_app.post("/api/estop", headers={"x-client-id": "bob"})
    assert r.status_code == 200 and robot.loop.hard_stop_engaged
    assert locked_app.post("/api/estop/release", headers={"x-client-id": "alice"}).status_code == 423
    r = locked_app.post("/api/estop/release", headers={"x-client-id": "alice", "x-lock-token": token})
    assert r.status_code == 200, r.text
    r = locked_app.put("/api/operator/velocity", json={"point": "rhand"}, headers={"x-lock-token": token})
    assert r.status_code == 200, r.text
    for headers in ({"x-client-id": "bob"}, {"x-client-id": "alice"}, {"x-lock-token": token[:-1]}):
        r = locked_app.delete("/api/operator/lock", headers=headers)
        assert r.status_code == 423 and r.json()["holder"] == "alice", r.text
    assert locked_app.get("/api/operator/lock").json()["holder"] == "alice"
    assert locked_app.delete("/api/operator/lock", headers={"x-lock-token": token}).json()["holder"] is None
    r = locked_app.put("/api/operator/velocity", json={"point": "rhand"}, headers={"x-client-id": "bob"})
    assert r.status_code == 200, r.text


def test_a_method_a_path_lacks_is_405_even_while_another_client_holds_the_lock(locked_app):
    token = _take(locked_app, "alice")
    r = locked_app.put("/api/behaviors", headers={"x-client-id": "bob"})  # GET only (the fuzz run found a 423)
    assert r.status_code == 405 and r.headers["allow"] == "GET", r.text
    assert locked_app.post("/api/walk/stop", headers={"x-client-id": "bob"}).status_code == 423
    locked_app.delete("/api/operator/lock", headers={"x-lock-token": token})


def test_a_stick_stream_without_the_holders_token_is_refused_naming_the_holder_and_the_socket_stays_usable(
        locked_app):
    token = _take(locked_app, "alice")
    for query in ("client=bob", "client=alice", "client=alice&lock_token=guessed"):
        with locked_app.websocket_connect(f"/ws/operator?{query}") as ws:
            ws.send_json({"point": "rhand", "linear": [0.01, 0, 0]})
            err = ws.receive_json()
            assert err["ok"] is False and err["reason"] == "locked" and err["holder"] == "alice", (query, err)
    with locked_app.websocket_connect(f"/ws/operator?client=alice&lock_token={token}") as ws:
        ws.send_json({"point": "rhand", "linear": [0.01, 0, 0]})
        assert ws.receive_json()["ok"] is True
        ws.send_json({"point": "rhand", "linear": [0, 0, 0]})
        assert ws.receive_json()["ok"] is True
    with locked_app.websocket_connect("/ws/operator?client=bob") as ws:
        ws.send_json({"point": "rhand", "linear": [0.01, 0, 0]})
        assert ws.receive_json()["reason"] == "locked"
        locked_app.delete("/api/operator/lock", headers={"x-lock-token": token})
        ws.send_json({"point": "rhand", "linear": [0.01, 0, 0]})
        ack = ws.receive_json()
        assert ack["ok"] is True, ack


def test_the_lock_is_released_a_grace_time_after_the_holders_last_websocket_closed(locked_app):
    import time

    token = _take(locked_app, "alice")
    with locked_app.websocket_connect("/ws/telemetry?client=alice&rate_hz=5") as ws:  # the name keeps nothing
        ws.receive_json()
        assert locked_app.get("/api/operator/lock").json()["connected"] is False
    with locked_app.websocket_connect(f"/ws/telemetry?client=alice&rate_hz=5&lock_token={token}") as ws:
        ws.receive_json()
        state = locked_app.get("/api/operator/lock").json()
        assert state["connected"] is True and state["expires_in_s"] is None
    state = locked_app.get("/api/operator/lock").json()
    assert state["holder"] == "alice" and state["connected"] is False and state["expires_in_s"] <= 0.2
    time.sleep(0.3)
    assert locked_app.get("/api/operator/lock").json()["holder"] is None


@pytest.mark.parametrize(("body", "field"), [({}, "client"), ({"client": ""}, "client"),
                                             ({"client": "a b"}, "client"), ({"client": "x" * 65}, "client"),
                                             ({"client": 7}, "client"), ({"client": "a", "extra": 1}, "extra")])
def test_an_invalid_client_id_is_422_naming_the_field(locked_app, body, field):
    r = locked_app.post("/api/operator/lock", json=body)
    assert r.status_code == 422, r.text
    assert r.json()["field"] == field


def test_the_lock_expires_after_its_lease_without_a_websocket_and_control_renews_it():
    now = [0.0]
    lock = OperatorLock(lease_s=5.0, grace_s=1.0, clock=lambda: now[0])
    _, alice = lock.take("alice")
    now[0] = 4.0
    assert lock.check(alice) is True  # a control request of the holder renews the lease
    now[0] = 8.9
    for token in (None, "alice", "bob"):
        with pytest.raises(Locked, match="held by 'alice'"):
            lock.check(token)
    now[0] = 9.0
    assert lock.check(None) is False  # expired: free
    assert lock.holder is None
    _, bob = lock.take("bob")
    assert bob != alice and not lock.holds(alice) and lock.holds(bob)
    assert lock.connected(alice) is None  # an old lease's socket keeps nothing
    lease = lock.connected(bob)
    now[0] = 100.0
    assert lock.holder == "bob"  # a holder with a WebSocket open keeps it
    lock.disconnected(lease)
    now[0] = 100.9
    assert lock.holder == "bob"
    now[0] = 101.0
    assert lock.holder is None


def test_taking_the_lock_with_the_holders_name_gives_no_token_and_release_needs_the_token():
    lock = OperatorLock()
    _, token = lock.take("alice")
    with pytest.raises(Locked):
        lock.take("alice")
    with pytest.raises(Locked):
        lock.release(None)
    with pytest.raises(Locked):
        lock.release("alice")
    assert lock.holder == "alice"
    lock.release(token)
    assert lock.holder is None


# ---- an unexpected error on a kept-alive connection -------------------------------------------------------------
@pytest.fixture
def served():
    """A running robot (real time) and its console app served by uvicorn on a loopback port, in this process
    (so a test can break a verb): (service, port)."""
    robot = LocalRobot(speed=1.0)
    robot.start()
    service = OperatorService(robot)
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.bind(("127.0.0.1", 0))
    server = uvicorn.Server(uvicorn.Config(create_app(Settings(), service=service), log_level="critical"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30.0
    while not server.started:
        assert time.monotonic() < deadline, "uvicorn did not start"
        time.sleep(0.02)
    try:
        yield service, sock.getsockname()[1]
    finally:
        server.should_exit = True
        thread.join(timeout=10.0)
        sock.close()
        robot.stop()


def _request(conn: http.client.HTTPConnection, method: str, path: str) -> tuple[int, dict, dict]:
    conn.request(method, path, body=b"{}" if method == "POST" else None, headers=JSON)
    r = conn.getresponse()
    raw = r.read()
    return r.status, json.loads(raw), dict(r.getheaders())


def test_an_unexpected_error_is_a_json_500_and_an_estop_on_the_same_connection_is_applied(served, monkeypatch):
    service, port = served

    def broken() -> str:
        raise RuntimeError("boom")

    monkeypatch.setattr(service, "clear_sequence", broken)  # POST /api/sequence/clear calls it
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    status, body, headers = _request(conn, "POST", "/api/sequence/clear")
    assert status == 500, body
    assert headers["content-type"] == "application/json" and body["detail"] == "internal error: RuntimeError: boom"
    sock = conn.sock
    status, body, _ = _request(conn, "POST", "/api/estop")  # the same keep-alive connection
    assert status == 200, body
    assert conn.sock is sock  # not reconnected: the server kept the connection open after the 500
    deadline = time.monotonic() + 5.0
    while True:
        status, state, _ = _request(conn, "GET", "/api/state")
        assert status == 200, state
        if state["emergency"]["hard_stop"]:
            break
        assert time.monotonic() < deadline, state["emergency"]
        time.sleep(0.05)
    assert conn.sock is sock
    conn.close()
