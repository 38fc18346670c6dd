"""The hard e-stop's own door into the robot process: a WebSocket listener served by the loop's thread between
ticks, as the e-stop pipe is. The operator page opens it beside its other sockets and sends `{"estop": true}` on
it first: that e-stop does not wait for the console process (its HTTP server, its streams and the 3D view share
one interpreter lock, and on a loaded machine the page's e-stop waited there 10-180 ms), and it still engages if
the console hangs.

It runs in the real-time process, so it takes as little as the e-stop needs and bounds the rest: at most
MAX_CLIENTS connections, messages of at most MAX_MESSAGE_BYTES, a handshake within HANDSHAKE_TIMEOUT_S, and per
tick at most READS_PER_TICK socket operations (an accept, or a read of at most RECV_BYTES): a client flooding it
(four of them sent 25,000 messages a second) made the loop's ticks up to 38 ms late before; the rest waits in the
sockets for the next tick. The same Host, Origin and token rules as the console's own door
(app.service.web_origin); one message, `{"estop": true}` or `{"estop": true, "press": "<id>"}` in any JSON
spelling, with the one semantics of every way in (app.service.estop), answered as POST /api/estop is. The
WebSocket protocol is websockets' sans-I/O implementation; no thread, no event loop: the loop's select() waits
on these sockets too. Whatever a client sends, an error in handling it drops that client only.
"""

from __future__ import annotations

import dataclasses
import hmac
import json
import logging
import select
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass
from urllib.parse import parse_qs, urlsplit

from websockets.frames import Frame, Opcode
from websockets.http11 import Request
from websockets.protocol import State
from websockets.server import ServerProtocol

from app.service import estop
from app.service.web_origin import host_name, origin_allowed, repeated_header

log = logging.getLogger(__name__)

MAX_CLIENTS = 8
MAX_MESSAGE_BYTES = 256
HANDSHAKE_TIMEOUT_S = 2.0
RECV_BYTES = 512  # a browser's handshake takes two reads; an e-stop frame is 21 bytes (15 and its framing)
READS_PER_TICK = 4


@dataclass(frozen=True)
class EstopDoorConfig:
    """Where the door listens and whom it lets in: `allowed_hosts` as the console's allowed_hosts_for (None: any
    Host, the page's Origin then the host it talks to); `token`: required as `?token=` or a Bearer header; a
    browser's Origin must be the console's page (app.service.web_origin.origin_allowed with `page_ports`)."""

    host: str = "127.0.0.1"
    port: int = 0  # 0: a free port, chosen at start (the page reads it from GET /api/config)
    allowed_hosts: tuple[str, ...] | None = ("127.0.0.1", "localhost", "::1")
    token: str | None = None
    page_ports: tuple[int, ...] = ()  # the ports the console's page is served on: the only Origins let in


class _Client:
    __slots__ = ("sock", "protocol", "since")

    def __init__(self, sock: socket.socket, now: float) -> None:
        self.sock = sock
        self.protocol = ServerProtocol(max_size=MAX_MESSAGE_BYTES)
        self.since = now


class EstopDoor:
    """The listener and its clients. `engage()` engages the hard e-stop and returns its acknowledgement (tick,
    sim_time_s, engaged_at_monotonic_s, already_engaged); `serve(readable)` handles the sockets select() found
    readable, `poll()` looks without waiting; `sockets` is what to wait on."""

    def __init__(self, config: EstopDoorConfig, engage: Callable[[str | None], object],
                 handshake_timeout_s: float = HANDSHAKE_TIMEOUT_S) -> None:
        self.config = config
        self._engage = engage
        self._handshake_timeout_s = handshake_timeout_s
        family = socket.AF_INET6 if ":" in config.host else socket.AF_INET
        self._listener = socket.create_server((config.host, config.port), family=family, backlog=MAX_CLIENTS)
        self._listener.setblocking(False)
        self.port: int = self._listener.getsockname()[1]
        self._allowed = None if config.allowed_hosts is None else frozenset(h.lower() for h in config.allowed_hosts)
        self._token = None if config.token is None else config.token.encode()
        self._clients: dict[socket.socket, _Client] = {}
        self.sockets: tuple[socket.socket, ...] = (self._listener,)  # what to wait on (none once the budget is spent)
        self._budget = READS_PER_TICK
        self._turn = 0  # where this tick's round starts among the readable sockets (no client starves another)
        self.engaged = 0  # e-stops engaged through the door (for the tests and the log)

    # ---- the loop's side ---------------------------------------------------------------------------------
    def new_tick(self) -> None:
        """A new tick: READS_PER_TICK socket operations again, every socket waited on."""
        self._budget = READS_PER_TICK
        self._update_sockets()

    def serve(self, readable) -> None:
        """Handle the readable sockets among `readable` (others are ignored) while this tick's budget lasts; drop
        handshakes that took too long. The readable sockets take turns: each tick's round starts one further."""
        readable = list(readable)
        if len(readable) > 1:
            k = self._turn % len(readable)
            readable = readable[k:] + readable[:k]
        self._turn += 1
        for sock in readable:
            if self._budget <= 0:
                break
            if sock is self._listener or sock in self._clients:
                self._budget -= 1
            if sock is self._listener:
                self._accept()
            else:
                client = self._clients.get(sock)
                if client is not None:
                    self._serve_client(client)
        if self._clients:
            self._expire(time.monotonic())
        if self._budget <= 0:
            self.sockets = ()  # spent: nothing more this tick (the loop does not wake for these sockets)

    def poll(self) -> None:
        """serve() whatever is readable now (no wait)."""
        if not self.sockets:
            return
        readable, _, _ = select.select(self.sockets, (), (), 0.0)
        if readable or self._clients:
            self.serve(readable)

    def close(self) -> None:
        for client in list(self._clients.values()):
            self._drop(client)
        self._listener.close()
        self._budget = 0
        self.sockets = ()

    # ---- connections ---------------------------------------------------------------------------------------
    def _accept(self) -> None:
        try:
            sock, _ = self._listener.accept()
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            log.warning("e-stop door: accept failed: %s", exc)
            return
        if len(self._clients) >= MAX_CLIENTS:
            sock.close()  # full: the page keeps its other ways in
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._clients[sock] = _Client(sock, time.monotonic())
        self._update_sockets()

    def _drop(self, client: _Client) -> None:
        self._clients.pop(client.sock, None)
        self._update_sockets()
        try:
            client.sock.close()
        except OSError:
            pass

    def _update_sockets(self) -> None:
        self.sockets = (self._listener, *self._clients) if self._budget > 0 else ()

    def _expire(self, now: float) -> None:
        for client in list(self._clients.values()):
            if client.protocol.state is State.CONNECTING and now - client.since > self._handshake_timeout_s:
                self._drop(client)

    def _serve_client(self, client: _Client) -> None:
        """One client's turn. Whatever its bytes do to the parsing, only this client is dropped: the loop goes on."""
        try:
            self._read(client)
        except Exception as exc:  # noqa: BLE001 - a hostile or broken client must never end the robot process
            # one line: formatting a traceback took the loop's thread up to 1.3 ms (its trace at debug level)
            log.warning("e-stop door: a client was dropped on an error: %s: %s", type(exc).__name__, exc)
            log.debug("e-stop door: the error", exc_info=True)
            self._drop(client)

    def _read(self, client: _Client) -> None:
        protocol = client.protocol
        try:
            data = client.sock.recv(RECV_BYTES)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._drop(client)
            return
        if not data:  # the client closed its side: what it sent before was answered, nothing more can be
            self._drop(client)
            return
        protocol.receive_data(data)
        for event in protocol.events_received():
            # only what the connection's state still lets be answered (the rest raised in the protocol, and a
            # raise costs the loop a logged error)
            if isinstance(event, Request) and protocol.state is State.CONNECTING and protocol.parser_exc is None:
                protocol.send_response(self._handshake(protocol, event))
            elif isinstance(event, Frame) and protocol.state is State.OPEN:
                if event.opcode is Opcode.TEXT:
                    protocol.send_text(self._answer(event).encode())
                elif event.opcode is Opcode.BINARY:
                    protocol.send_text(json.dumps({"ok": False, "estop": True, "detail": _ONLY}).encode())
        self._flush(client)

    def _flush(self, client: _Client) -> None:
        protocol = client.protocol
        try:
            for chunk in protocol.data_to_send():
                if chunk:
                    client.sock.sendall(chunk)  # a few hundred bytes: the socket buffer takes them
                else:  # the protocol is done with the connection
                    self._drop(client)
                    return
        except OSError:  # including a full buffer: a client that does not read is dropped
            self._drop(client)
            return
        if protocol.state is State.CLOSED:
            self._drop(client)

    # ---- what it answers -----------------------------------------------------------------------------------
    def _handshake(self, protocol: ServerProtocol, request: Request):
        headers = request.headers
        repeated = repeated_header(headers.raw_items())
        if repeated is not None:
            return protocol.reject(400, f"header {repeated} given more than once\n")
        unreadable = next((name for name, value in headers.raw_items() if not value.isascii()), None)
        if unreadable is not None:  # its bytes could not even be quoted back in websockets' own refusal
            return protocol.reject(400, f"header {unreadable} has bytes outside ASCII\n")
        host = headers.get("Host", "")
        if self._allowed is not None and host_name(host) not in self._allowed:
            return protocol.reject(421, "this console does not answer for that Host\n")
        if not origin_allowed(headers.get("Origin"), host, self._allowed, self.config.page_ports):
            return protocol.reject(403, "cross-origin e-stops are refused; use the console's own page\n")
        if self._token is not None:
            auth = headers.get("Authorization", "")
            given = auth[7:].strip() if auth[:7].lower() == "bearer " else None
            if given is None:
                values = parse_qs(urlsplit(request.path).query).get("token")
                given = values[-1] if values else None
            if given is None or not hmac.compare_digest(given.encode("utf-8", "replace"), self._token):
                return protocol.reject(401, "token missing or wrong: connect with ?token=<the console's token>\n")
        return protocol.accept(request)

    def _answer(self, frame: Frame) -> str:
        request = estop.parse_text(frame.data)
        if request is None:
            return json.dumps({"ok": False, "estop": True, "detail": _ONLY})
        try:
            ack = self._engage(request.press)
        except Exception as exc:  # noqa: BLE001 - said to the client; the loop goes on (the other doors too)
            log.error("e-stop door: engaging failed: %s", exc)
            return json.dumps({"ok": False, "estop": True, "detail": f"the e-stop could not be engaged: {exc}"})
        self.engaged += 1
        if request.press_ignored is not None:
            ack = dataclasses.replace(ack, press_ignored=request.press_ignored)
        return json.dumps({**ack.reply(via="door"), "estop": True})


_ONLY = 'this door takes one message, {"estop": true} (with its press\'s id: {"estop": true, "press": "<id>"})'
