"""The e-stop's own door into the robot process (app.service.estop_door): what it lets in, what it answers,
and how it bounds what it takes, driven as the robot's loop drives it (select on its sockets, then serve)."""

import dataclasses
import json
import select
import socket
import threading
import time

import pytest
from websockets.exceptions import ConnectionClosed, ConnectionClosedError, InvalidHandshake, InvalidStatus
from websockets.sync.client import connect

from app.service.estop import EstopAck
from app.service.estop_door import (
    MAX_CLIENTS,
    MAX_MESSAGE_BYTES,
    READS_PER_TICK,
    RECV_BYTES,
    EstopDoor,
    EstopDoorConfig,
)

PAGE_PORT = 8000
PAGE = f"http://127.0.0.1:{PAGE_PORT}"  # the console's page: an allowed host, the page's port
CONFIG = EstopDoorConfig(page_ports=(PAGE_PORT,))


class Served:
    """A door served by a thread as the robot's loop serves it, and what its engage() was asked."""

    def __init__(self, config: EstopDoorConfig, fail: bool = False, handshake_timeout_s: float = 2.0) -> None:
        self.calls = 0
        self.presses: list[str | None] = []  # the press id of each call
        self.fail = fail
        self.door = EstopDoor(config, self._engage, handshake_timeout_s=handshake_timeout_s)
        self.url = f"ws://127.0.0.1:{self.door.port}/"
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _engage(self, press=None):
        self.calls += 1
        self.presses.append(press)
        if self.fail:
            raise RuntimeError("the loop is gone")
        return EstopAck(tick=42, sim_time_s=0.21, engaged_at_monotonic_s=time.monotonic(), engaged=True,
                        already_engaged=self.calls > 1)

    def _run(self) -> None:
        while not self._stop.is_set():  # a 5 ms "tick": its budget, then what is readable within it
            self.door.new_tick()
            deadline = time.monotonic() + 0.005
            while (left := deadline - time.monotonic()) > 0:
                readable, _, _ = select.select(self.door.sockets, (), (), left)
                self.door.serve(readable)

    def close_thread_only(self) -> None:
        """Stop serving from the thread (the test serves the door itself from now on)."""
        self._stop.set()
        self._thread.join(timeout=2.0)

    def close(self) -> None:
        self.close_thread_only()
        self.door.close()


@pytest.fixture
def served():
    s = Served(CONFIG)
    yield s
    s.close()


def estop(ws) -> dict:
    ws.send(json.dumps({"estop": True}))
    return json.loads(ws.recv(timeout=2.0))


def test_an_estop_on_the_door_engages_and_is_answered_as_post_api_estop(served):
    with connect(served.url, origin=PAGE) as ws:
        first = estop(ws)
        second = estop(ws)
    assert served.calls == 2
    assert first["ok"] and first["estop"] and first["via"] == "door" and first["message"] == "hard e-stop engaged"
    assert first["tick"] == 42 and first["sim_time_s"] == 0.21 and first["engaged_at_monotonic_s"] > 0.0
    assert second["message"] == "hard e-stop already engaged"


def test_a_press_id_is_handed_to_the_loop_and_a_bad_one_engages_without_it_saying_so(served):
    with connect(served.url, origin=PAGE) as ws:
        ws.send(json.dumps({"estop": True, "press": "page-ab12:7"}))
        good = json.loads(ws.recv(timeout=2.0))
        bad = []
        for press in ["", "x" * 65, "a b", 7, ["p"]]:
            ws.send(json.dumps({"estop": True, "press": press}))
            bad.append(json.loads(ws.recv(timeout=2.0)))
    assert good["ok"] and good["engaged"] and "press_ignored" not in good
    assert served.presses == ["page-ab12:7", None, None, None, None, None]  # a malformed id never blocks a stop
    for reply in bad:
        assert reply["ok"] and reply["engaged"] and "1 to 64 characters" in reply["press_ignored"], reply


@pytest.mark.parametrize("message", ['{ "estop": true }', '{"press": "k1", "estop": true}', '{\n  "estop": true\n}',
                                     '{"\\u0065stop": true}', '{"estop": true, "x": 1}'])
def test_any_json_spelling_of_an_estop_engages(served, message):
    with connect(served.url, origin=PAGE) as ws:
        ws.send(message)
        reply = json.loads(ws.recv(timeout=2.0))
    assert reply["ok"] and served.calls == 1, reply


def test_a_script_without_an_origin_may_press_it(served):
    with connect(served.url) as ws:
        assert estop(ws)["ok"]


@pytest.mark.parametrize("origin", ["http://evil.example", "http://127.0.0.1.evil.example:8000", "null",
                                    "http://localhost:9999", "http://127.0.0.1:9999", "http://127.0.0.1",
                                    "http://[::1]:9999", "ftp://127.0.0.1:8000", "http://127.0.0.1:8000/x",
                                    "http://127.0.0.1:99999"])
def test_a_page_of_another_site_is_refused_before_any_message(served, origin):
    with pytest.raises(InvalidStatus) as exc:
        connect(served.url, origin=origin)
    assert exc.value.response.status_code == 403
    assert served.calls == 0


@pytest.mark.parametrize("name", ["Host", "Origin", "Authorization", "Sec-WebSocket-Key"])
def test_a_handshake_with_a_repeated_header_is_refused_and_the_door_goes_on(served, name):
    """Two Origin (Host, ...) headers: which one a check would read is not what a later reader might use."""
    headers = [("Host", f"127.0.0.1:{served.door.port}"), ("Upgrade", "websocket"), ("Connection", "Upgrade"),
               ("Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="), ("Sec-WebSocket-Version", "13"), ("Origin", PAGE),
               ("Authorization", "Bearer x")]
    headers += [(k, v) for k, v in headers if k == name]
    request = "GET / HTTP/1.1\r\n" + "".join(f"{k}: {v}\r\n" for k, v in headers) + "\r\n"
    with socket.create_connection(("127.0.0.1", served.door.port), timeout=3.0) as raw:
        raw.sendall(request.encode())
        answer = raw.recv(200)
    assert answer.startswith(b"HTTP/1.1 400"), answer
    with connect(served.url, origin=PAGE) as ws:
        assert estop(ws)["ok"]


def handshake(port: int, extra: bytes = b"") -> bytes:
    return (f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\nOrigin: {PAGE}\r\n"
            ).encode() + extra + b"\r\n"


def test_a_header_with_bytes_outside_ascii_is_refused_naming_it(served, caplog):
    """websockets' own refusal quoted such a value back and failed to encode it: the client was dropped on an
    error, logged from the loop's thread."""
    with socket.create_connection(("127.0.0.1", served.door.port), timeout=3.0) as raw:
        raw.sendall(handshake(served.door.port, b"Sec-WebSocket-Protocol: \xff\xfe\r\n"))
        answer = raw.recv(300)
    assert answer.startswith(b"HTTP/1.1 400") and b"Sec-WebSocket-Protocol has bytes outside ASCII" in answer, answer
    with connect(served.url, origin=PAGE) as ws:
        assert estop(ws)["ok"]
    assert not [r for r in caplog.records if "dropped on an error" in r.getMessage()]


@pytest.mark.parametrize("sent", [
    "a handshake cut short by the client closing its side",
    "a refused handshake and bytes that are no frame in one write",
    "an e-stop and a close frame in one write",
    "a close frame, then an e-stop",
])
def test_a_client_breaking_off_mid_handshake_or_mid_close_is_dropped_without_an_error(served, caplog, sent):
    """A request completed by the client's EOF, or a frame after the client's close, raised in the protocol (an
    assertion, an invalid state) and the loop's thread logged it with its trace: up to 1.3 ms of a tick."""
    def frame(opcode: int, payload: bytes) -> bytes:  # a client's frame: masked with a zero mask
        return bytes([0x80 | opcode, 0x80 | len(payload)]) + b"\0\0\0\0" + payload

    with socket.create_connection(("127.0.0.1", served.door.port), timeout=3.0) as raw:
        if sent.startswith("a handshake"):
            raw.sendall(handshake(served.door.port)[:-2])
            raw.shutdown(socket.SHUT_WR)
        elif sent.endswith("one write") and sent.startswith("a refused"):
            raw.sendall(handshake(served.door.port).replace(PAGE.encode(), b"http://evil.example") + b"\x0fno frame")
        else:
            raw.sendall(handshake(served.door.port))
            assert raw.recv(300).startswith(b"HTTP/1.1 101")
            close = frame(0x8, b"\x03\xe8")
            press = frame(0x1, json.dumps({"estop": True}).encode())
            raw.sendall(press + close if sent.startswith("an e-stop") else close + press)
        raw.settimeout(3.0)
        while raw.recv(300):  # until the door closes the connection
            pass
    with connect(served.url, origin=PAGE) as ws:
        assert estop(ws)["ok"]
    assert not [r for r in caplog.records if "dropped on an error" in r.getMessage()]


def test_a_host_it_does_not_answer_for_is_refused():
    s = Served(dataclasses.replace(CONFIG, allowed_hosts=("localhost",)))
    try:
        with pytest.raises(InvalidStatus) as exc:
            connect(s.url, origin="http://localhost:8000")  # Host: 127.0.0.1:port
        assert exc.value.response.status_code == 421
        with connect(f"ws://localhost:{s.door.port}/", origin="http://localhost:8000") as ws:
            assert estop(ws)["ok"]
    finally:
        s.close()


def test_with_a_token_it_takes_the_token_in_the_query_or_as_a_bearer_header_and_nothing_else():
    s = Served(dataclasses.replace(CONFIG, token="a-long-enough-secret-token"))
    try:
        for url, headers in ((s.url, None), (s.url + "?token=wrong", None),
                             (s.url, {"Authorization": "Bearer wrong"})):
            with pytest.raises(InvalidStatus) as exc:
                connect(url, origin=PAGE, additional_headers=headers)
            assert exc.value.response.status_code == 401
        assert s.calls == 0
        with connect(s.url + "?token=a-long-enough-secret-token", origin=PAGE) as ws:
            assert estop(ws)["ok"]
        bearer = {"Authorization": "Bearer a-long-enough-secret-token"}
        with connect(s.url, origin=PAGE, additional_headers=bearer) as ws:
            assert estop(ws)["ok"]
    finally:
        s.close()


@pytest.mark.parametrize("message", ['{"estop": false}', '{"estop": 1}', "estop", "[]", '"estop"', b"\x00"])
def test_any_other_message_is_answered_with_what_it_takes_and_engages_nothing(served, message):
    with connect(served.url, origin=PAGE) as ws:
        ws.send(message)
        reply = json.loads(ws.recv(timeout=2.0))
        assert reply == {"ok": False, "estop": True, "detail": 'this door takes one message, {"estop": true} (with '
                                                              'its press\'s id: {"estop": true, "press": "<id>"})'}
        assert estop(ws)["ok"]  # the same connection still works
    assert served.calls == 1


def test_an_oversized_message_closes_that_connection_and_the_door_goes_on(served):
    with connect(served.url, origin=PAGE) as ws:
        ws.send("x" * (MAX_MESSAGE_BYTES + 1))
        with pytest.raises(ConnectionClosedError) as exc:
            ws.recv(timeout=2.0)
        assert exc.value.rcvd.code == 1009
    assert served.calls == 0
    with connect(served.url, origin=PAGE) as ws:
        assert estop(ws)["ok"]


def test_it_holds_at_most_max_clients_connections(served):
    open_ = [connect(served.url, origin=PAGE) for _ in range(MAX_CLIENTS)]
    try:
        with pytest.raises((InvalidHandshake, ConnectionClosed, OSError)):  # closed at once: no HTTP answer
            connect(served.url, origin=PAGE, open_timeout=2.0)
        open_.pop().close()
        deadline = time.monotonic() + 2.0
        while len(served.door.sockets) > MAX_CLIENTS and time.monotonic() < deadline:  # the close seen
            time.sleep(0.01)
        with connect(served.url, origin=PAGE) as ws:
            assert estop(ws)["ok"]
    finally:
        for ws in open_:
            ws.close()


def test_a_connection_that_never_completes_its_handshake_is_dropped():
    s = Served(CONFIG, handshake_timeout_s=0.2)
    try:
        with socket.create_connection(("127.0.0.1", s.door.port), timeout=3.0) as raw:
            raw.sendall(b"GET / HTTP/1.1\r\n")  # and nothing more
            assert raw.recv(100) == b""  # closed by the door, not by this timeout
    finally:
        s.close()


def test_an_engage_that_fails_is_said_and_the_door_goes_on():
    s = Served(CONFIG, fail=True)
    try:
        with connect(s.url, origin=PAGE) as ws:
            reply = estop(ws)
            assert reply["ok"] is False and "the loop is gone" in reply["detail"]
            s.fail = False
            assert estop(ws)["ok"]
    finally:
        s.close()


def one_tick(door: EstopDoor) -> None:
    """Serve the door as the loop does over one tick, by hand: a new budget, then what is readable until it is spent
    (or nothing more comes within 50 ms)."""
    door.new_tick()
    while door.sockets:
        readable, _, _ = select.select(door.sockets, (), (), 0.05)
        if not readable:
            break
        door.serve(readable)


def test_a_flood_is_served_a_bounded_share_per_tick_and_the_rest_waits_for_the_next_ticks():
    """At most READS_PER_TICK socket operations per tick, each of at most RECV_BYTES: 200 e-stops sent at once are
    answered over several ticks, never more per tick than those reads hold (a client's e-stop frame is 21 bytes:
    15, a 2-byte header, a 4-byte mask),
    and once the budget is spent the door gives the loop nothing to wait on until the next tick."""
    s = Served(CONFIG)
    ws = connect(s.url, origin=PAGE)
    s.close_thread_only()
    try:
        for _ in range(200):
            ws.send('{"estop": true}')
        time.sleep(0.2)  # all of them in the door's socket buffer
        per_tick = []
        for _ in range(1000):
            before = s.calls
            one_tick(s.door)
            per_tick.append(s.calls - before)
            if s.calls == 200:
                break
        assert s.calls == 200  # every one answered in the end
        assert max(per_tick) <= READS_PER_TICK * (RECV_BYTES // 21 + 1), per_tick
        assert len(per_tick) >= 200 / (READS_PER_TICK * (RECV_BYTES // 21 + 1))
        replies = [json.loads(ws.recv(timeout=2.0)) for _ in range(200)]
        assert all(r["ok"] for r in replies)
    finally:
        s.door.close()  # first: the client's close then finds the connection gone, not waiting for an answer
        ws.close()


def test_clients_flooding_it_do_not_starve_another_clients_estop():
    """Four clients with 200 junk messages each queued, then one e-stop from a fifth: the readable sockets take
    turns, so the e-stop is answered within two ticks of its arrival, not after the junk."""
    s = Served(CONFIG)
    floods = [connect(s.url, origin=PAGE) for _ in range(4)]
    page = connect(s.url, origin=PAGE)
    s.close_thread_only()
    try:
        for ws in floods:
            for _ in range(200):
                ws.send("x" * 20)
        page.send('{"estop": true}')
        time.sleep(0.2)
        tick = 0
        while not s.calls and tick < 100:
            tick += 1
            one_tick(s.door)
        assert s.calls == 1 and tick <= 2, f"the e-stop was answered at tick {tick}"
        assert json.loads(page.recv(timeout=2.0))["ok"]
    finally:
        s.door.close()
        for ws in (*floods, page):
            ws.close()
