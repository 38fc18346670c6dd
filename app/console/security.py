"""The console's front door (pure ASGI middleware): Host and Origin checks against DNS rebinding and
cross-site requests, the access token, the operator lock, JSON-only control requests, a body-size limit,
and a JSON 500 for anything unexpected that keeps the connection usable."""

from __future__ import annotations

import hmac
import ipaddress
import json
import logging
import os
from collections.abc import Iterable
from urllib.parse import parse_qs

from app.console.operator_lock import TOKEN_HEADER, Locked, OperatorLock
from app.service.web_origin import (  # noqa: F401 - the console's front door and the robot's e-stop door share them
    DEFAULT_PORTS,
    SINGLE_HEADERS,
    host_name,
    origin_allowed,
    repeated_header,
    split_origin,
)

log = logging.getLogger(__name__)

MAX_BODY_BYTES = 64 * 1024
#: a refused body up to this size is read and discarded before the 413 ends, so that a client that sends its whole
#: body before reading can read the answer; a larger one is answered at once and the connection closed
DRAIN_MAX_BYTES = 16 * 1024 * 1024
UNSAFE_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})
#: control requests any page may send without a JSON body: they can only make the robot safer
ALWAYS_ALLOWED = frozenset({("POST", "/api/estop")})
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
#: control requests the operator lock never refuses: stops (they only make the robot safer) and the lock's own
LOCK_EXEMPT = frozenset({("POST", "/api/estop"), ("POST", "/api/motion/stop"), ("POST", "/api/operator/lock"),
                         ("DELETE", "/api/operator/lock")})
#: paths that need the token when one is set (everything else: the page, its static files, /docs, the schema)
TOKEN_PREFIXES = ("/api/", "/ws/")
TOKEN_ENV = "HRP2_CONSOLE_TOKEN"
MIN_TOKEN_CHARS = 16
CLIENT_HEADER = b"x-client-id"  # the client's display name (journal, point ownership): it authenticates nothing
LOCK_TOKEN_HEADER = TOKEN_HEADER.lower().encode()  # the operator lock's lease token: the holder's proof


def is_loopback(host: str) -> bool:
    if host in ("localhost",):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


class TokenRequired(ValueError):
    """The console cannot start as configured: a host other than loopback without a (good) token."""


def token_from_env(given: str | None) -> str | None:
    """`--token` if given, else the environment's HRP2_CONSOLE_TOKEN, else None."""
    if given is not None:
        return given
    return os.environ.get(TOKEN_ENV) or None


def check_token_config(host: str, token: str | None) -> None:
    """TokenRequired when the console would answer other machines without a token, or with a weak one."""
    if token is not None:
        if len(token) < MIN_TOKEN_CHARS or any(c.isspace() for c in token) or not token.isprintable():
            raise TokenRequired(f"the token must be at least {MIN_TOKEN_CHARS} printable characters without "
                                f"spaces (got {len(token)}); e.g. python3 -c 'import secrets; "
                                "print(secrets.token_urlsafe())'")
        return
    if not is_loopback(host):
        raise TokenRequired(f"--host {host} lets other machines reach the console: give a token with --token "
                            f"or the environment variable {TOKEN_ENV} (at least {MIN_TOKEN_CHARS} characters), "
                            "or bind 127.0.0.1 (the default)")


def allowed_hosts_for(bind_host: str, extra: Iterable[str] = ()) -> tuple[str, ...] | None:
    """Host names a request may carry for a server bound to `bind_host`; None: any (bound to every
    interface, where the token of the console guards instead)."""
    if bind_host in ("0.0.0.0", "::", ""):
        return None
    names = {bind_host, *extra}
    if is_loopback(bind_host):
        names |= set(LOOPBACK_NAMES)
    return tuple(sorted(names))


async def _send_json(send, status: int, detail: str, headers: Iterable[tuple[bytes, bytes]] = ()) -> None:
    payload = json.dumps({"detail": detail}).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(payload)).encode()),
                            *headers]})
    await send({"type": "http.response.body", "body": payload})


class ConsoleGuard:
    """Wraps the FastAPI app. `allowed_hosts` None accepts any Host (the token then guards, see Settings).
    `token`: when set, every /api/ request carries it as `Authorization: Bearer <token>` and every /ws/
    connection as `?token=<token>` (or the same header). `lock`: while a client holds it, the control
    requests that do not carry its lease token (header X-Lock-Token) are answered 423 naming the holder (stops
    excepted, see LOCK_EXEMPT)."""

    def __init__(self, app, allowed_hosts: tuple[str, ...] | None, max_body_bytes: int = MAX_BODY_BYTES,
                 token: str | None = None, lock: OperatorLock | None = None) -> None:
        self.app = app
        self.allowed_hosts = None if allowed_hosts is None else frozenset(h.lower() for h in allowed_hosts)
        self.max_body_bytes = max_body_bytes
        self._token = None if token is None else token.encode()
        self.lock = lock

    def _token_ok(self, scope, headers: dict[bytes, bytes]) -> bool:
        if self._token is None or not scope["path"].startswith(TOKEN_PREFIXES):
            return True
        auth = headers.get(b"authorization", b"")
        given = auth[7:].strip() if auth[:7].lower() == b"bearer " else None
        if given is None and scope["type"] == "websocket":
            values = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token")
            given = values[-1].encode("latin-1", "replace") if values else None
        return given is not None and hmac.compare_digest(given, self._token)

    def _documented(self, scope) -> bool:
        """Whether the API has this method at this path (True when the app cannot tell)."""
        allowed = getattr(self.app, "allowed_methods", None)
        if allowed is None:
            return True
        methods = allowed(scope)
        return methods is None or scope["method"] in methods

    def _host_ok(self, headers: dict[bytes, bytes]) -> bool:
        if self.allowed_hosts is None:
            return True
        host = headers.get(b"host", b"").decode("latin-1")
        return host_name(host) in self.allowed_hosts

    def _origin_ok(self, headers: dict[bytes, bytes]) -> bool:
        origin = headers.get(b"origin")
        return origin_allowed(None if origin is None else origin.decode("latin-1"),
                              headers.get(b"host", b"").decode("latin-1"), self.allowed_hosts)

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {k.lower(): v for k, v in scope.get("headers", [])}
        repeated = repeated_header(scope.get("headers", ()))
        if repeated is not None:
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008})
                return
            await _send_json(send, 400, f"header {repeated} given more than once; send it once")
            return
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
            if not self._token_ok(scope, headers):
                await send({"type": "websocket.close", "code": 1008,
                            "reason": "token missing or wrong: connect with ?token=<the console's token>"})
                return
            await self.app(scope, receive, send)
            return
        method = scope["method"]
        path = scope["path"]
        if not self._token_ok(scope, headers):
            await _send_json(send, 401, "token missing or wrong: send the console's token as "
                                        "'Authorization: Bearer <token>' (the page takes it from its URL, "
                                        "/?token=...)", [(b"www-authenticate", b"Bearer")])
            return
        if method in UNSAFE_METHODS:
            if not self._origin_ok(headers):
                await _send_json(send, 403, "cross-origin control requests are refused; use the console's own page")
                return
            if (self.lock is not None and path.startswith("/api/") and (method, path) not in LOCK_EXEMPT
                    and self._documented(scope)):  # a method the path lacks is answered 405, locked or not
                lease = headers.get(LOCK_TOKEN_HEADER)
                try:
                    self.lock.check(None if lease is None else lease.decode("latin-1"), f"{method} {path}")
                except Locked as exc:
                    payload = json.dumps({"detail": str(exc), "reason": "locked", "holder": exc.holder}).encode()
                    await send({"type": "http.response.start", "status": 423, "headers": [
                        (b"content-type", b"application/json"), (b"content-length", str(len(payload)).encode())]})
                    await send({"type": "http.response.body", "body": payload})
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
                expects_continue = headers.get(b"expect", b"").lower() == b"100-continue"  # nothing sent yet
                await _refuse_body(receive, send, f"the body is {n} bytes; the limit is {self.max_body_bytes}",
                                   drain=n <= DRAIN_MAX_BYTES and not expects_continue)
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
                    await _refuse_body(receive, send, f"the body is over the limit of {self.max_body_bytes} bytes",
                                       drain=more)
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


async def _refuse_body(receive, send, detail: str, drain: bool) -> None:
    """413 with `detail`, then the connection is closed. With `drain`, the rest of the body (up to
    DRAIN_MAX_BYTES) is read and discarded before the answer ends: a server that closes a socket with unread
    bytes in it resets the connection, and a client still sending its body then never reads the answer."""
    payload = json.dumps({"detail": detail}).encode()
    await send({"type": "http.response.start", "status": 413,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(payload)).encode()),
                            (b"connection", b"close")]})
    await send({"type": "http.response.body", "body": payload, "more_body": True})
    discarded = 0
    while drain and discarded <= DRAIN_MAX_BYTES:
        message = await receive()
        if message["type"] == "http.disconnect":
            break
        discarded += len(message.get("body", b""))
        drain = message.get("more_body", False)
    await send({"type": "http.response.body", "body": b""})
