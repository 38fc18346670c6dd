"""Hostile and broken clients on every socket that parses a client's bytes for the robot: the robot process's own
e-stop door, and the console's /ws/operator and /ws/telemetry. Over 10,000 generated inputs (hypothesis):
repeated, missing, oversized and malformed headers, random bytes, lying and oversized WebSocket frames, slow and
half-closed clients, against a real console paced at real time. The robot process must stay alive, keep its ticks
on time, and engage an e-stop a well-behaved page sends in the middle of it."""

from __future__ import annotations

import base64
import json
import os
import socket
import struct
import threading
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from websockets.sync.client import connect

from app.lab.console_process import Console
from app.service import estop

pytestmark = pytest.mark.slow
#: hostile connections, over the three sockets: handshakes, then bursts of frames after an accepted handshake
#: (FUZZ_SOCKET_EXAMPLES=40000 for a longer run)
EXAMPLES = int(os.environ.get("FUZZ_SOCKET_EXAMPLES", "10200"))
HANDSHAKE_SHARE = 0.6
LATENESS_MARGIN_MS = 0.5  # the bound over idle
TIMING_WINDOW_S = 10.0  # the idle p99, and the printed ones under fuzz, are over windows of 2,000 ticks
#: [s] the asserted p99 under fuzz is the issue's, over the fuzz's last minute (the 12,000 ticks the loop keeps; the
#: fuzz takes 60-90 s), not per 10-s window: a window can hold a burst of hypervisor steal (0.75 % of the cores over
#: one run; 0.1-ms select()s waking 0.4-2.9 ms late with nothing to serve), which no client input causes
FUZZ_WINDOW_S = 60.0
DT_CONTROL_S = 0.005  # the console's default tick
KEY = base64.b64encode(b"0123456789abcdef").decode()


class Target:
    """One of the sockets under attack: where it listens and the request a well-formed client would send."""

    def __init__(self, port: int, path: str, page_port: int) -> None:
        self.port, self.path, self.page_port = port, path, page_port

    def headers(self) -> list[tuple[bytes, bytes]]:
        return [(b"Host", f"127.0.0.1:{self.port}".encode()), (b"Upgrade", b"websocket"),
                (b"Connection", b"Upgrade"), (b"Sec-WebSocket-Key", KEY.encode()), (b"Sec-WebSocket-Version", b"13"),
                (b"Origin", f"http://127.0.0.1:{self.page_port}".encode())]


# ---- what a hostile client sends ---------------------------------------------------------------------------
HEADER_NAMES = [b"Host", b"Origin", b"Authorization", b"Upgrade", b"Connection", b"Sec-WebSocket-Key",
                b"Sec-WebSocket-Version", b"Sec-WebSocket-Protocol", b"Sec-WebSocket-Extensions", b"Content-Length",
                b"Transfer-Encoding", b"X-Client-Id", b"Cookie"]
values = st.one_of(
    st.binary(max_size=40),
    st.sampled_from([b"", b"websocket", b"Upgrade", b"13", b"8", b"null", b"http://evil.example", b"http://127.0.0.1",
                     b"http://localhost:9999", b"Bearer ", b"permessage-deflate; client_max_window_bits", b"-1",
                     b"\xff\xfe", "\u00e9".encode(), b"a\r\nInjected: 1"]),
    st.integers(2000, 20000).map(lambda n: b"v" * n),  # oversized
)
mutations = st.lists(st.one_of(
    st.tuples(st.just("drop"), st.integers(0, 5)),
    st.tuples(st.just("repeat"), st.integers(0, 5)),
    st.tuples(st.just("set"), st.integers(0, 5), values),
    st.tuples(st.just("add"), st.sampled_from(HEADER_NAMES) | st.binary(min_size=1, max_size=20), values),
), max_size=4)
request_lines = st.one_of(
    st.sampled_from([b"GET {path} HTTP/1.1", b"GET {path} HTTP/1.0", b"POST {path} HTTP/1.1", b"GET  HTTP/1.1",
                     b"GET {path}?token=x&token=y HTTP/1.1", b"GET /%ff HTTP/1.1", b"GET * HTTP/1.1", b"\x16\x03\x01"]),
    st.binary(max_size=60),
)
endings = st.sampled_from(["read", "read", "close", "half_close", "slow"])


def handshake_bytes(target: Target, line: bytes, muts, terminator: bytes, tail: bytes) -> bytes:
    headers = target.headers()
    for m in muts:
        if m[0] == "drop" and headers:
            headers.pop(m[1] % len(headers))
        elif m[0] == "repeat" and headers:
            headers.append(headers[m[1] % len(headers)])
        elif m[0] == "set" and headers:
            i = m[1] % len(headers)
            headers[i] = (headers[i][0], m[2])
        elif m[0] == "add":
            headers.append((m[1], m[2]))
    head = line.replace(b"{path}", target.path.encode()) + b"\r\n"
    return head + b"".join(k + b": " + v + b"\r\n" for k, v in headers) + terminator + tail


def frame_bytes(opcode: int, fin: bool, rsv: int, masked: bool, payload: bytes, length_lie: int | None) -> bytes:
    """A WebSocket frame as a client would write it, or with its flags, mask and length wrong."""
    n = len(payload) if length_lie is None else length_lie
    first = (0x80 if fin else 0) | (rsv & 0x7) << 4 | (opcode & 0xF)
    if n < 126:
        head = struct.pack("!BB", first, (0x80 if masked else 0) | n)
    elif n < 1 << 16:
        head = struct.pack("!BBH", first, (0x80 if masked else 0) | 126, n)
    else:
        head = struct.pack("!BBQ", first, (0x80 if masked else 0) | 127, n)
    if not masked:
        return head + payload
    mask = b"\x12\x34\x56\x78"
    return head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


json_values = st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=10),
                           lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner,
                                                                                       max_size=4), max_leaves=12)
near_setpoints = st.fixed_dictionaries({
    "point": st.sampled_from(["rhand", "lhand", "head", "walk", "nope", "", "RHAND"]),
    "linear": st.sampled_from([[1e9, 0, 0], ["x", 0, 0], [0, 0], [float("nan"), 0, 0], None, "fast"]),
}).map(lambda d: json.dumps(d).encode())
near_pings = st.one_of(  # the streams' {"ping": X} (echoed as {"pong": X}) with what X must not be
    st.builds(lambda v: json.dumps({"ping": v}).encode(), json_values),
    st.sampled_from([b'{"ping": 1e999}', b'{"ping": NaN}', b'{"ping": 1' + b"0" * 400 + b"}",
                     b'{"rate_hz": 1' + b"0" * 400 + b"}", b'{"ping": 1, "rate_hz": 5}']),
)
payloads = st.one_of(
    st.binary(max_size=80),
    json_values.map(lambda v: json.dumps(v).encode()),
    near_setpoints,
    near_pings,
    st.sampled_from([b'{"estop": false}', b'{"estop": "true"}', b'{"estop": 1}', b"[" * 5000, b'{"a":' * 300,
                     b"\xff" * 50, b"{}", b"null"]),
    st.integers(4000, 70000).map(lambda n: b"x" * n),  # over every limit
).filter(lambda p: estop.parse_text(p) is None)  # the hostile clients never press the e-stop themselves
frames = st.builds(frame_bytes, opcode=st.sampled_from([0x0, 0x1, 0x1, 0x2, 0x3, 0x8, 0x9, 0xA, 0xF]),
                   fin=st.booleans(), rsv=st.sampled_from([0, 0, 0, 4, 7]), masked=st.booleans() | st.just(True),
                   payload=payloads, length_lie=st.none() | st.none() | st.integers(0, 1 << 40))


def _read_briefly(sock: socket.socket, timeout_s: float) -> bytes:
    sock.settimeout(timeout_s)
    try:
        return sock.recv(4096)
    except OSError:
        return b""


def send_as(sock: socket.socket, data: bytes, ending: str) -> None:
    try:
        if ending == "slow":  # a trickle: the server must not wait on it with anyone else's time
            for i in range(0, len(data), max(1, len(data) // 3)):
                sock.sendall(data[i:i + max(1, len(data) // 3)])
                time.sleep(0.002)
        else:
            sock.sendall(data)
        if ending == "half_close":
            sock.shutdown(socket.SHUT_WR)
        if ending in ("read", "half_close"):
            _read_briefly(sock, 0.02)
    except OSError:
        pass  # the server closed on us: that is an answer too


def opened(target: Target) -> socket.socket | None:
    """A connection whose handshake the server accepted (None: refused, e.g. the door full)."""
    sock = socket.create_connection(("127.0.0.1", target.port), timeout=2.0)
    sock.sendall(handshake_bytes(target, b"GET {path} HTTP/1.1", [], b"\r\n", b""))
    answer = b""
    while b"\r\n\r\n" not in answer:
        more = _read_briefly(sock, 2.0)
        if not more:
            sock.close()
            return None
        answer += more
    if not answer.startswith(b"HTTP/1.1 101"):
        sock.close()
        return None
    return sock


# ---- the well-behaved page ------------------------------------------------------------------------------
class Page(threading.Thread):
    """Presses the e-stop on the door every `every_s` (a new press id each time, as the page does), checks the loop
    has it engaged, releases it; meanwhile notes the loop's lateness."""

    def __init__(self, console: Console, door_port: int, every_s: float = 2.0) -> None:
        super().__init__(daemon=True)
        self.console, self.door_port, self.every_s = console, door_port, every_s
        self.done = threading.Event()
        self.presses: list[tuple[bool, bool]] = []  # (answered ok, the loop's state said engaged)
        self.p99_ms: list[float] = []  # tick start-lateness p99 of each window of TIMING_WINDOW_S
        self.max_ms: list[float] = []
        self.errors: list[str] = []

    def run(self) -> None:
        n = 0
        last_timing = time.monotonic()
        while not self.done.wait(self.every_s):
            n += 1
            try:
                self._press(f"fuzz-page:{n}")
            except Exception as exc:  # noqa: BLE001 - reported by the test
                self.errors.append(f"press {n}: {type(exc).__name__}: {exc}")
            if time.monotonic() - last_timing >= TIMING_WINDOW_S:
                last_timing = time.monotonic()
                self.note_timing()

    def note_timing(self) -> None:
        status, timing = self.console.request("GET", f"/api/loop/timing?last_s={TIMING_WINDOW_S:g}")
        if status == 200:
            self.p99_ms.append(timing["lateness_p99_ms"])
            self.max_ms.append(timing["lateness_max_ms"])

    def _press(self, press: str) -> None:
        url = f"ws://127.0.0.1:{self.door_port}/"
        with connect(url, origin=f"http://127.0.0.1:{self.console.port}", open_timeout=2.0) as ws:
            ws.send(json.dumps({"estop": True, "press": press}))
            reply = json.loads(ws.recv(timeout=2.0))
        self.presses.append((bool(reply.get("ok")), self.console.hard_stop_after(reply.get("tick", -1))))
        status, body = self.console.request("POST", "/api/estop/release")
        if status != 200:
            self.errors.append(f"release {press}: {status} {body}")


@pytest.fixture(scope="module")
def console():
    with Console("--speed", "1.0") as c:
        yield c


def idle_p99_ms(console: Console) -> float:
    time.sleep(TIMING_WINDOW_S)
    status, timing = console.request("GET", f"/api/loop/timing?last_s={TIMING_WINDOW_S:g}")
    assert status == 200
    return timing["lateness_p99_ms"]


def test_no_client_bytes_end_or_delay_the_robot_and_a_pages_estop_engages_throughout(console):
    _, cfg = console.request("GET", "/api/config")
    _, health = console.request("GET", "/api/health")
    assert health["robot_alive"]
    idle = idle_p99_ms(console)
    targets = {"door": Target(cfg["estop_port"], "/", console.port),
               "operator": Target(console.port, "/ws/operator", console.port),
               "telemetry": Target(console.port, "/ws/telemetry", console.port)}
    page = Page(console, cfg["estop_port"])
    page.start()
    counts = {"handshakes": 0, "frame bursts": 0, "frames": 0, "refused handshakes": 0}
    started = time.monotonic()
    try:
        @given(target=st.sampled_from(sorted(targets)), line=request_lines, muts=mutations,
               terminator=st.sampled_from([b"\r\n", b"\r\n", b"", b"\n", b"\r\n\r\n\r\n"]),
               tail=st.binary(max_size=30), ending=endings)
        @settings(max_examples=round(EXAMPLES * HANDSHAKE_SHARE), deadline=None, database=None,
                  suppress_health_check=list(HealthCheck))
        def handshakes(target, line, muts, terminator, tail, ending):
            with socket.create_connection(("127.0.0.1", targets[target].port), timeout=2.0) as sock:
                send_as(sock, handshake_bytes(targets[target], line, muts, terminator, tail), ending)
            counts["handshakes"] += 1

        @given(target=st.sampled_from(sorted(targets)), burst=st.lists(frames, min_size=1, max_size=4),
               ending=endings)
        @settings(max_examples=EXAMPLES - round(EXAMPLES * HANDSHAKE_SHARE), deadline=None, database=None,
                  suppress_health_check=list(HealthCheck))
        def frames_after_a_handshake(target, burst, ending):
            sock = opened(targets[target])
            if sock is None:
                counts["refused handshakes"] += 1
                return
            with sock:
                send_as(sock, b"".join(burst), ending)
            counts["frame bursts"] += 1
            counts["frames"] += len(burst)

        handshakes()
        frames_after_a_handshake()
    finally:
        page.done.set()
        page.join(timeout=10.0)
        page.note_timing()  # the last window
    fuzzed_s = time.monotonic() - started
    window_s = min(FUZZ_WINDOW_S, float(int(fuzzed_s)))
    _, fuzzed = console.request("GET", f"/api/loop/timing?last_s={window_s:g}")
    _, health = console.request("GET", "/api/health")
    inputs = counts["handshakes"] + counts["frame bursts"]
    print(f"\nsocket fuzz: {inputs} hostile connections ({counts}); tick lateness p99 idle {idle:.3f} ms, under fuzz "
          f"{fuzzed['lateness_p99_ms']:.3f} ms over the last {window_s:g} s of {fuzzed_s:.0f} s (per "
          f"{TIMING_WINDOW_S:g} s: {', '.join(f'{v:.3f}' for v in page.p99_ms)} ms; max "
          f"{', '.join(f'{v:.2f}' for v in page.max_ms)} ms); {len(page.presses)} e-stops pressed by the page")
    assert health["robot_alive"], health
    assert console.proc.poll() is None  # and the console itself
    assert inputs >= EXAMPLES - 10 and counts["refused handshakes"] <= EXAMPLES // 100, counts
    assert not page.errors, page.errors
    assert len(page.presses) >= 3 and all(ok and engaged for ok, engaged in page.presses), page.presses
    # the bound is the robot process's own: with its real-time priority refused (health's "priority"), the
    # machine's other processes take its cores (measured without it: p99 0.7-2.8 ms on 2 cores)
    assert window_s >= FUZZ_WINDOW_S / 2 and fuzzed["ticks"] >= 0.9 * window_s / DT_CONTROL_S, (window_s, fuzzed)
    assert fuzzed["lateness_p99_ms"] <= idle + LATENESS_MARGIN_MS, (idle, fuzzed, page.p99_ms, health["priority"])
