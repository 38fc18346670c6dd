"""The console's front door (pure ASGI middleware): Host and Origin checks against DNS rebinding and
cross-site requests, JSON-only control requests, a body-size limit, and a JSON 500 for anything
unexpected that keeps the connection usable."""

from __future__ import annotations

import ipaddress
import json
import logging
from collections.abc import Iterable

log = logging.getLogger(__name__)

MAX_BODY_BYTES = 64 * 1024
UNSAFE_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})
#: control requests any page may send without a JSON body: they can only make the robot safer
ALWAYS_ALLOWED = frozenset({("POST", "/api/estop")})
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")


def is_loopback(host: str) -> bool:
    if host in ("localhost",):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def allowed_hosts_for(bind_host: str, extra: Iterable[str] = ()) -> tuple[str, ...] | None:
    """Host names a request may carry for a server bound to `bind_host`; None: any (bound to every
    interface, where the token of the console guards instead)."""
    if bind_host in ("0.0.0.0", "::", ""):
        return None
    names = {bind_host, *extra}
    if is_loopback(bind_host):
        names |= set(LOOPBACK_NAMES)
    return tuple(sorted(names))


def _host_name(host_header: str) -> str:
    """The name part of a Host header ("[::1]:8000" -> "::1", "localhost:8000" -> "localhost")."""
    h = host_header.strip().lower()
    if h.startswith("["):
        return h[1:h.find("]")] if "]" in h else h
    return h.rsplit(":", 1)[0] if h.count(":") == 1 else h


def _origin_host(origin: str) -> tuple[str, str] | None:
    """(scheme, host name) of an Origin header, or None if it is "null" or malformed."""
    if "://" not in origin:
        return None
    scheme, rest = origin.split("://", 1)
    return scheme.lower(), _host_name(rest.split("/", 1)[0])


async def _send_json(send, status: int, detail: str, headers: Iterable[tuple[bytes, bytes]] = ()) -> None:
    payload = json.dumps({"detail": detail}).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(payload)).encode()),
                            *headers]})
    await send({"type": "http.response.body", "body": payload})


class ConsoleGuard:
    """Wraps the FastAPI app. `allowed_hosts` None accepts any Host (the token then guards, see Settings)."""

    def __init__(self, app, allowed_hosts: tuple[str, ...] | None, max_body_bytes: int = MAX_BODY_BYTES) -> None:
        self.app = app
        self.allowed_hosts = None if allowed_hosts is None else frozenset(h.lower() for h in allowed_hosts)
        self.max_body_bytes = max_body_bytes

    def _host_ok(self, headers: dict[bytes, bytes]) -> bool:
        if self.allowed_hosts is None:
            return True
        host = headers.get(b"host", b"").decode("latin-1")
        return _host_name(host) in self.allowed_hosts

    def _origin_ok(self, headers: dict[bytes, bytes]) -> bool:
        origin = headers.get(b"origin")
        if origin is None:
            return True  # not a browser's cross-origin request (curl, scripts, same-origin GET)
        parsed = _origin_host(origin.decode("latin-1"))
        if parsed is None:
            return False
        if self.allowed_hosts is None:
            # any interface: the page must come from the host it talks to
            return parsed[1] == _host_name(headers.get(b"host", b"").decode("latin-1"))
        return parsed[1] in self.allowed_hosts

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {k.lower(): v for k, v in scope.get("headers", [])}
        if not self._host_ok(headers):
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008})
                return
            await _send_json(send, 421, "this console does not answer for that Host (allowed: "
                                        f"{', '.join(sorted(self.allowed_hosts or ()))})")
            return
        if scope["type"] == "websocket":
            if not self._origin_ok(headers):
                await send({"type": "websocket.close", "code": 1008})
                return
            await self.app(scope, receive, send)
            return
        method = scope["method"]
        path = scope["path"]
        if method in UNSAFE_METHODS:
            if not self._origin_ok(headers):
                await _send_json(send, 403, "cross-origin control requests are refused; use the console's own page")
                return
            ctype = headers.get(b"content-type", b"").decode("latin-1").split(";")[0].strip().lower()
            if ctype != "application/json" and (method, path) not in ALWAYS_ALLOWED:
                await _send_json(send, 415, "control requests must be sent with Content-Type: application/json "
                                            "(a page of another site cannot send that without asking first)")
                return
        length = headers.get(b"content-length")
        if length is not None:
            try:
                n = int(length)
            except ValueError:
                await _send_json(send, 400, "invalid Content-Length")
                return
            if n > self.max_body_bytes:
                await _send_json(send, 413, f"the body is {n} bytes; the limit is {self.max_body_bytes}")
                return
        if method in UNSAFE_METHODS:
            body = b""
            more = True
            while more:
                message = await receive()
                if message["type"] == "http.disconnect":
                    return
                body += message.get("body", b"")
                more = message.get("more_body", False)
                if len(body) > self.max_body_bytes:
                    await _send_json(send, 413, f"the body is over the limit of {self.max_body_bytes} bytes")
                    return
            if body.strip():
                try:
                    json.loads(body.decode("utf-8"))
                except UnicodeDecodeError as exc:
                    await _send_json(send, 422, f"body: not UTF-8 ({exc.reason} at byte {exc.start})")
                    return
                except RecursionError:
                    await _send_json(send, 422, "body: JSON nested too deeply")
                    return
                except ValueError:
                    pass  # FastAPI answers invalid JSON with a 422 that says where
            replayed = False

            async def receive_buffered():
                nonlocal replayed
                if not replayed:
                    replayed = True
                    return {"type": "http.request", "body": body, "more_body": False}
                return await receive()

            inner_receive = receive_buffered
        else:
            inner_receive = receive
        started = False

        async def send_tracked(message):
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, inner_receive, send_tracked)
        except RecursionError:
            if not started:
                await _send_json(send, 422, "body: nested too deeply")
        except Exception as exc:  # noqa: BLE001 - answered, logged, and the connection stays open
            if not started:
                log.exception("request %s %s failed", method, path)
                await _send_json(send, 500, f"internal error: {type(exc).__name__}: {exc}")
