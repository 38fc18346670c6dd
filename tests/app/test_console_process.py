"""The console as users run it (`hrp2-console --headless`: HTTP in one process, the robot in another),
attacked the way a stranger would: bad requests on a kept-alive connection, foreign origins and hosts,
huge bodies, signals, and pollers."""

import json
import signal
import socket
import time

import pytest

from app.lab.console_process import Console, run_load

HUGE = "1" + "0" * 400  # 10**400 written out: no float holds it
#: (method, path, the field given HUGE, the field the 422 names): every request that takes layer parameters
PARAM_REQUESTS = [
    ("PUT", "/api/stabilizer/params", "transition_time_s", "transition_time_s"),
    ("PUT", "/api/auto-balancer/params", "transition_time_s", "transition_time_s"),
    ("PUT", "/api/impedance/rarm/params", "k_p", "k_p"),
    ("PUT", "/api/emergency-stopper/params", "t1", "t1"),
    ("PUT", "/api/operator/params", "hand_speed_m_s", "hand_speed_m_s"),
    ("PUT", "/api/params", "st.k1", "st.k1"),
    ("POST", "/api/experiments/wall-push-left", "params.t1", "params.t1"),
]


def nested_body(dotted: str, value: str) -> str:
    """{"a": {"b": value}} for "a.b", with `value` written verbatim."""
    body = value
    for key in reversed(dotted.split(".")):
        body = f'{{"{key}": {body}}}'
    return body


@pytest.fixture(scope="module")
def console():
    with Console("--speed", "1.0") as c:
        yield c


def wait_for(console, path, predicate, timeout_s=10.0):
    """GET `path` until `predicate(document)` holds; the document."""
    deadline = time.monotonic() + timeout_s
    while True:
        status, doc = console.request("GET", path)
        if status == 200 and predicate(doc):
            return doc
        assert time.monotonic() < deadline, f"{path} not as expected: {doc}"
        time.sleep(0.05)


def wait_state(console, predicate, timeout_s=10.0):
    return wait_for(console, "/api/state", predicate, timeout_s)


def wait_health(console, predicate, timeout_s=10.0):
    return wait_for(console, "/api/health", predicate, timeout_s)


def test_a_bad_parameter_request_then_an_estop_on_the_same_connection_is_applied(console):
    conn = console.connection()
    status, body = console.request("PUT", "/api/stabilizer/params", body=nested_body("k1", HUGE), conn=conn)
    assert status == 422 and body["field"] == "k1" and "finite" in body["detail"]
    status, body = console.request("POST", "/api/estop", conn=conn)  # the same keep-alive connection
    assert status == 200, body
    wait_state(console, lambda s: s["emergency"]["hard_stop"])
    status, _ = console.request("POST", "/api/estop/release", conn=conn)
    assert status == 200
    wait_state(console, lambda s: not s["emergency"]["hard_stop"])
    conn.close()


@pytest.mark.parametrize(("method", "path", "given", "field"), PARAM_REQUESTS,
                         ids=[f"{m} {p}" for m, p, _, _ in PARAM_REQUESTS])
def test_every_parameter_request_answers_a_huge_integer_with_a_422_naming_the_field(console, method, path, given,
                                                                                    field):
    status, body = console.request(method, path, body=nested_body(given, HUGE))
    assert status == 422, body
    assert body["field"] == field and "finite" in body["detail"]


@pytest.mark.parametrize(("method", "path", "headers", "expected"), [
    ("POST", "/api/estop/release", {"Origin": "http://evil.example"}, 403),
    ("POST", "/api/sim/reset", {"Origin": "http://evil.example"}, 403),
    ("POST", "/api/motion/release", {"Content-Type": "text/plain"}, 415),
    ("POST", "/api/stabilizer/stop", {"Content-Type": "application/x-www-form-urlencoded"}, 415),
    ("POST", "/api/experiments/wall-push-left", {"Content-Type": "multipart/form-data; boundary=x"}, 415),
    ("GET", "/api/state", {"Host": "evil.example"}, 421),
    ("POST", "/api/estop", {"Host": "rebound.example:8000"}, 421),
], ids=["origin-release", "origin-reset", "text-plain", "form", "multipart", "foreign-host", "rebinding-estop"])
def test_cross_site_requests_and_foreign_hosts_are_refused(console, method, path, headers, expected):
    status, body = console.request(method, path, headers=headers)
    assert status == expected, body
    state = wait_state(console, lambda s: True)
    assert not state["emergency"]["stabilizer_stop"] and not state["emergency"]["hard_stop"]


def test_an_estop_needs_no_json_body_and_any_page_of_this_host_may_send_it(console):
    status, _ = console.request("POST", "/api/estop", headers={"Content-Type": "text/plain"})
    assert status == 200
    wait_state(console, lambda s: s["emergency"]["hard_stop"])
    assert console.request("POST", "/api/estop/release")[0] == 200


def test_the_estop_door_of_the_robot_process_engages_even_while_the_console_process_is_stopped(console):
    """GET /api/config names the e-stop's own door; an e-stop on it engages in the robot process while the
    console (HTTP) process is frozen (SIGSTOP): the e-stop does not depend on the server the page talks to."""
    import json

    from websockets.sync.client import connect

    port = console.request("GET", "/api/config")[1]["estop_port"]
    assert isinstance(port, int) and port > 0
    with connect(f"ws://127.0.0.1:{port}/", origin=f"http://127.0.0.1:{console.port}", open_timeout=5) as ws:
        console.proc.send_signal(signal.SIGSTOP)
        try:
            sent = time.monotonic()
            ws.send('{"estop": true}')
            reply = json.loads(ws.recv(timeout=5.0))
        finally:
            console.proc.send_signal(signal.SIGCONT)
    assert reply["ok"] and reply["via"] == "door" and reply["message"] == "hard e-stop engaged"
    assert sent <= reply["engaged_at_monotonic_s"]  # engaged after it was sent (both on this machine's clock)
    wait_state(console, lambda s: s["emergency"]["hard_stop"])
    assert console.request("POST", "/api/estop/release")[0] == 200
    wait_state(console, lambda s: not s["emergency"]["hard_stop"])


def test_a_websocket_message_over_the_limit_is_refused_by_the_server_with_1009_and_it_serves_on(console):
    """uvicorn's ws_max_size is the 4 kB message limit: the server closes the socket from the frame's length
    (1009, message too big) instead of reading the message for the app to refuse (which answers in-process
    with an error and keeps the socket, tests/app/test_ws_messages.py)."""
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    from app.console.ws import MAX_MESSAGE_BYTES

    url = f"ws://127.0.0.1:{console.port}/ws/operator"
    with connect(url, open_timeout=5) as ws:
        ws.send("x" * (16 * MAX_MESSAGE_BYTES))
        with pytest.raises(ConnectionClosed) as caught:
            ws.recv(timeout=5.0)
    assert caught.value.rcvd is not None and caught.value.rcvd.code == 1009, caught.value
    with connect(url, open_timeout=5) as ws:  # a message at the limit still reaches the app
        ws.send(json.dumps({"point": "rhand", "linear": [0, 0, 0]}).ljust(MAX_MESSAGE_BYTES))
        assert json.loads(ws.recv(timeout=5.0))["ok"] is True
    assert console.request("GET", "/api/health")[0] == 200


def test_a_10_mb_body_is_refused_with_413_and_no_tick_is_late_meanwhile(console):
    t0 = time.monotonic()
    status, body = console.request("PUT", "/api/stabilizer/params", body=b"{" + b" " * (10 * 1024 * 1024) + b"}")
    elapsed = time.monotonic() - t0
    assert status == 413, body
    time.sleep(0.1)
    status, timing = console.request("GET", f"/api/loop/timing?last_s={elapsed + 0.3:.3f}")
    assert status == 200
    assert timing["lateness_max_ms"] <= 10.0, timing


def _read_reply(sock) -> bytes:
    """One HTTP reply off `sock`: the head, then as many body bytes as its Content-Length says (the head and the
    body may come in separate segments)."""
    data = b""
    while b"\r\n\r\n" not in data:
        part = sock.recv(65536)
        if not part:
            return data
        data += part
    head, _, body = data.partition(b"\r\n\r\n")
    length = next((int(line.split(b":", 1)[1]) for line in head.split(b"\r\n")
                   if line.lower().startswith(b"content-length:")), 0)
    while len(body) < length:
        part = sock.recv(65536)
        if not part:
            break
        body += part
    return head + b"\r\n\r\n" + body


def test_a_chunked_body_without_a_length_is_cut_off_at_the_limit_with_413(console):
    # no Content-Length to refuse it by: the server counts as it reads and answers before the 10 MB are sent
    with socket.create_connection(("127.0.0.1", console.port), timeout=30) as sock:
        sock.sendall(b"PUT /api/stabilizer/params HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                     b"Content-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n")
        chunk = b" " * 16384
        for _ in range(8):  # 128 kB of the 10 MB, twice the limit: then the answer is read
            sock.sendall(f"{len(chunk):x}\r\n".encode() + chunk + b"\r\n")
        reply = _read_reply(sock).decode(errors="replace")
    assert reply.startswith("HTTP/1.1 413"), reply[:200]
    assert "over the limit of 65536 bytes" in reply
    assert console.request("GET", "/api/health")[0] == 200  # the console serves on


def test_a_10_mb_body_sent_whole_before_reading_gets_a_readable_413_and_beyond_16_mb_it_is_answered_at_once(console):
    """The server reads and discards a refused body up to 16 MB before it ends the 413 and closes: a client that
    sends all 10 MB first (here on a connection it asked to close, which the server closes after the answer)
    then reads the answer, where the close used to reset the connection under the unread body."""
    from app.console.security import DRAIN_MAX_BYTES

    body = b"{" + b" " * (10 * 1024 * 1024) + b"}"
    with socket.create_connection(("127.0.0.1", console.port), timeout=30) as sock:
        sock.sendall(b"PUT /api/stabilizer/params HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n"
                     b"Content-Type: application/json\r\nContent-Length: %d\r\n\r\n" % len(body) + body)
        reply = _read_reply(sock).decode(errors="replace")
    head, _, payload = reply.partition("\r\n\r\n")
    assert head.startswith("HTTP/1.1 413"), reply[:200]
    assert json.loads(payload) == {"detail": f"the body is {len(body)} bytes; the limit is 65536"}
    # beyond the bound the server does not read: it answers from the length, at once, and closes
    with socket.create_connection(("127.0.0.1", console.port), timeout=30) as sock:
        sock.sendall(b"PUT /api/stabilizer/params HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                     b"Content-Type: application/json\r\nContent-Length: %d\r\n\r\n{" % (DRAIN_MAX_BYTES + 1))
        reply = _read_reply(sock).decode(errors="replace")
        assert sock.recv(1) == b""  # closed
    assert reply.startswith("HTTP/1.1 413") and "connection: close" in reply.lower(), reply[:200]
    assert console.request("GET", "/api/health")[0] == 200  # the console serves on


def test_unexpected_input_shapes_are_422s_not_500s(console):
    for path, body in [("/api/walk/go-pos", '{"x": "-30", "y": 0, "theta_deg": 0}'),
                       ("/api/walk/go-pos", '{"x": true, "y": 0, "theta_deg": 0}'),
                       ("/api/sequence/joint-angles", '{"angles_deg": {"RARM_JOINT0": 1}, "time": 5e-324}'),
                       ("/api/sim/push", '[' * 5000 + ']' * 5000),
                       ("/api/params", '{"st": {"k1": "a"}}'),
                       ("/api/params", '{"nope": {"k1": 1}}')]:
        status, reply = console.request("POST" if "params" not in path else "PUT", path, body=body)
        assert status in (404, 422), (path, status, reply)
        assert isinstance(reply["detail"], str)


@pytest.mark.slow
def test_twenty_pollers_and_a_hundred_commands_a_second_do_not_make_the_loop_late(console):
    duration_s = 30.0
    r = run_load(console, duration_s)
    loop = r["loop"]
    print(f"\n{r['polls_per_s']:.0f} polls/s, {r['commands_per_s']:.0f} commands/s: tick start-lateness "
          f"p50 {loop['lateness_p50_ms']:.3f} p99 {loop['lateness_p99_ms']:.3f} max {loop['lateness_max_ms']:.3f} ms; "
          f"slowest 1-s window {loop['speed_min']:.3f} x real time; /api/state p99 {r['state_request']['p99_ms']} ms")
    assert not r["errors"]
    assert r["polls_per_s"] > 0.8 * 20 * 10 and r["commands_per_s"] > 0.8 * 100
    assert loop["lateness_p99_ms"] <= 5.0
    assert loop["speed_min"] >= 0.9


def test_sigterm_and_sigint_shut_the_console_down_cleanly_with_the_summary():
    for sig in (signal.SIGTERM, signal.SIGINT):
        with Console("--speed", "max") as c:
            health = wait_health(c, lambda h: h["run"] is not None and h["run"]["ticks"] > 0)
            assert health["robot_alive"] is True
            # no fault, no fall: the run's own counters (the summary below prints them)
            assert health["run"]["faults"] == [] and health["run"]["fallen"] is False
            code, out = c.stop(sig)
            assert code == 0, out  # the console exits 1 when its counters hold a fault or a fall
            # the text is the behaviour here: the signal named and the summary printed on the way out
            assert f"{signal.Signals(sig).name} received" in out, out
            assert "summary:" in out and "faults: none" in out and "fallen: false" in out
