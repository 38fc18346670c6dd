"""Who may knock on a door: the Host and Origin checks, and the headers a request may carry only once. Plain
functions of the request's headers, shared by the console's front door (app.console.security) and the robot
process's e-stop door (app.service.estop_door), which must not depend on the console."""

from __future__ import annotations

from collections.abc import Collection, Iterable
from urllib.parse import urlsplit

#: headers a request may carry once only: with two, which one a check reads and which one a later reader uses
#: could differ
SINGLE_HEADERS = frozenset({"host", "origin", "authorization", "content-length", "x-client-id", "x-estop-press",
                            "sec-websocket-key", "upgrade", "connection", "content-type"})


def repeated_header(headers: Iterable[tuple[bytes | str, bytes | str]]) -> str | None:
    """The first of SINGLE_HEADERS given more than once (None: none)."""
    seen: set[str] = set()
    for name, _ in headers:
        key = (name.decode("latin-1") if isinstance(name, bytes) else name).lower()
        if key in SINGLE_HEADERS:
            if key in seen:
                return key
            seen.add(key)
    return None


def host_name(host_header: str) -> str:
    """The name part of a Host header ("[::1]:8000" -> "::1", "localhost:8000" -> "localhost")."""
    h = host_header.strip().lower()
    if h.startswith("["):
        return h[1:h.find("]")] if "]" in h else h
    return h.rsplit(":", 1)[0] if h.count(":") == 1 else h


DEFAULT_PORTS = {"http": 80, "https": 443}


def split_origin(origin: str) -> tuple[str, str, int] | None:
    """(scheme, host name, port) of an Origin header ("http://[::1]:8000" -> ("http", "::1", 8000)); None for
    "null", a scheme other than http(s), or anything malformed."""
    try:
        parts = urlsplit(origin.strip())
        port = parts.port
    except ValueError:
        return None
    scheme = parts.scheme.lower()
    if scheme not in DEFAULT_PORTS or not parts.hostname or parts.path or parts.query or parts.username:
        return None
    return scheme, parts.hostname.lower(), DEFAULT_PORTS[scheme] if port is None else port


def origin_allowed(origin: str | None, host_header: str, allowed_hosts: frozenset[str] | None,
                   ports: Collection[int] | None = None) -> bool:
    """Whether a request with this Origin comes from one of the console's own pages: scheme http(s), host among
    `allowed_hosts` (None: the host the request was sent to), port among `ports` (None: the port the request was
    sent to, i.e. the same origin). No Origin at all: not a browser's cross-origin request (a script). One
    function for the HTTP API, its WebSockets, the robot's e-stop door and the 3D view."""
    if origin is None:
        return True
    parsed = split_origin(origin)
    if parsed is None:
        return False
    scheme, name, port = parsed
    try:
        sent_to = urlsplit("//" + host_header.strip())
        sent_to_port = sent_to.port or DEFAULT_PORTS[scheme]
    except ValueError:
        return False
    if allowed_hosts is None:
        if name != (sent_to.hostname or ""):
            return False
    elif name not in allowed_hosts:
        return False
    return port in ports if ports is not None else port == sent_to_port
