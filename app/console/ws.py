"""The console's WebSockets, shared by the routers that serve them: the message size limit, the `?client=<id>`
check (a display name), the operator lock's lease token (`?lock_token=`), receiving a text message, and a stream
at a rate its client chooses (`?rate_hz=N`, then {"rate_hz": N} messages: the opening checks, the operator lock
kept by its holder's `?lock_token=`, the sends under one lock, and the reader that answers rate messages and
{"ping": X} ones with {"pong": X}, the page's round trip on its own stream). The
telemetry and the camera streams are built on it; each says only what it sends."""

from __future__ import annotations

import asyncio
import json
import math

from fastapi import WebSocket

from app.console.deps import get_lock
from app.console.operator_lock import TOKEN_HEADER, TOKEN_PARAM, check_client_id

MAX_MESSAGE_BYTES = 4096  # a setpoint is ~150 bytes


def ws_client(ws: WebSocket) -> tuple[str | None, str | None]:
    """(the ?client= id or None, an error message naming the field)."""
    client = ws.query_params.get("client")
    if client is None:
        return None, None
    try:
        return check_client_id(client, "client"), None
    except ValueError as exc:
        return None, str(exc)


def ws_lock_token(ws: WebSocket) -> str | None:
    """The operator lock's lease token the socket was opened with (?lock_token=, or the X-Lock-Token header)."""
    return ws.query_params.get(TOKEN_PARAM) or ws.headers.get(TOKEN_HEADER)


def ws_sender_name(ws: WebSocket, client: str | None) -> str:
    """The name a stream's client is shown by: its ?client= id, else "anonymous@<address>"."""
    if client is not None:
        return client
    peer = ws.client
    return f"anonymous@{peer.host if peer else '?'}"


async def receive_message(ws: WebSocket) -> str | None:
    """The next text message; None when the client left. A binary message is answered by the caller as
    invalid (it gets b"" here)."""
    message = await ws.receive()
    if message["type"] == "websocket.disconnect":
        return None
    text = message.get("text")
    return "" if text is None else text


def error_text(detail: str, field: str | None = None) -> str:
    """{"ok": false, "detail", "field"} as a JSON text message."""
    return json.dumps({k: v for k, v in {"ok": False, "detail": detail, "field": field}.items() if v is not None})


def check_rate(value: object, range_hz: tuple[float, float]) -> float:
    """A rate [Hz] inside `range_hz` (a number, or a string of one), or ValueError saying what is allowed."""
    lo, hi = range_hz
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise ValueError(f"rate_hz: {value!r} is not a number; give {lo:g} to {hi:g} [Hz]") from None
    if isinstance(value, int) and not isinstance(value, bool) and not lo <= value <= hi:  # (one too big for a float)
        raise ValueError(f"rate_hz: {str(value)[:20]} Hz is outside the allowed range [{lo:g}, {hi:g}] Hz")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"rate_hz: {value!r} is not a number; give {lo:g} to {hi:g} [Hz]")
    if not lo <= value <= hi:
        raise ValueError(f"rate_hz: {value:g} Hz is outside the allowed range [{lo:g}, {hi:g}] Hz")
    return float(value)


PING_MAX = 1e15  # [any unit] a ping's value is the client's (a clock reading): bounded so its echo stays short


def client_message(text: str, range_hz: tuple[float, float]) -> tuple[str, float]:
    """("rate_hz", N) for a {"rate_hz": N} message, ("ping", X) for a {"ping": X} one (X a finite number the
    client chooses, echoed as {"pong": X}: its round trip on this socket), or ValueError naming the field."""
    if not text:
        raise ValueError("body: send {\"rate_hz\": N} or {\"ping\": X} as a JSON text message")
    try:
        msg = json.loads(text)
    except ValueError as exc:
        raise ValueError(f"body: invalid JSON ({exc})") from None
    if not isinstance(msg, dict):
        raise ValueError("body: send a JSON object {\"rate_hz\": N} or {\"ping\": X}")
    unknown = sorted(set(msg) - {"rate_hz", "ping"})
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown field; the fields are rate_hz and ping")
    if len(msg) != 1:
        raise ValueError("body: send one field, rate_hz or ping" if msg else "rate_hz: field required")
    if "ping" in msg:
        value = msg["ping"]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not abs(value) <= PING_MAX:  # (NaN)
            raise ValueError(f"ping: {str(value)[:40]!r} is not allowed; give a finite number within "
                             f"+-{PING_MAX:g} (it is echoed as pong)")
        return "ping", value
    return "rate_hz", check_rate(msg["rate_hz"], range_hz)


def _field(exc: ValueError) -> str:
    return str(exc).split(":", 1)[0]


class RateStream:
    """One accepted stream: `period_s` (changed by the client's messages), `send`, `reading` (the reader task:
    done when the client has gone), `close()`."""

    def __init__(self, ws: WebSocket, range_hz: tuple[float, float], rate_hz: float, lease: str | None) -> None:
        self.ws = ws
        self.range_hz = range_hz
        self.period_s = 1.0 / rate_hz
        self.lease = lease  # the operator lock's lease this stream keeps (None: none)
        self.lock = get_lock(ws)
        self.send_lock = asyncio.Lock()
        self.reading: asyncio.Task | None = None

    @classmethod
    async def open(cls, ws: WebSocket, range_hz: tuple[float, float], default_hz: float) -> RateStream | None:
        """Accept; a bad `?rate_hz` or `?client` is answered with an error naming it and the socket closed
        (None). Otherwise the operator lock is kept while the stream is open if it was opened with the holder's
        ?lock_token=, and the reader runs."""
        lock = get_lock(ws)
        _, bad_client = ws_client(ws)  # the name is only checked: it keeps no lock
        await ws.accept()
        try:
            rate = check_rate(ws.query_params.get("rate_hz", default_hz), range_hz)
            if bad_client is not None:
                raise ValueError(bad_client)
        except ValueError as exc:
            await ws.send_text(error_text(str(exc), field=_field(exc)))
            await ws.close(code=1008, reason=str(exc)[:120])
            return None
        stream = cls(ws, range_hz, rate, lock.connected(ws_lock_token(ws)))
        stream.reading = asyncio.create_task(stream._reader())
        return stream

    async def send(self, text: str) -> None:
        async with self.send_lock:
            await self.ws.send_text(text)

    async def wait(self, timeout_s: float) -> None:
        """Sleep up to `timeout_s`, or until the client goes."""
        await asyncio.wait({self.reading}, timeout=max(0.0, timeout_s))

    async def _reader(self) -> None:
        while True:
            text = await receive_message(self.ws)
            if text is None:
                return
            if len(text) > MAX_MESSAGE_BYTES:
                await self.send(error_text(f"body: message of {len(text)} bytes; the limit is {MAX_MESSAGE_BYTES}",
                                           "body"))
                continue
            try:
                kind, value = client_message(text, self.range_hz)
            except ValueError as exc:
                await self.send(error_text(str(exc), field=_field(exc)))
                continue
            if kind == "ping":
                await self.send(json.dumps({"pong": value}))
                continue
            self.period_s = 1.0 / value
            await self.send(json.dumps({"ok": True, "rate_hz": round(1.0 / self.period_s, 6)}))

    def close(self) -> None:
        if self.reading is not None:
            self.reading.cancel()
        self.lock.disconnected(self.lease)
        self.lease = None
