"""WS /ws/telemetry: the /api/state document pushed at a rate the client chooses (1-50 Hz), for the page and
for scripts. A message {"rate_hz": N} changes the rate; an invalid one is answered with an error naming the
field, and the stream goes on."""

from __future__ import annotations

import asyncio
import json
import logging
import math
import time

from fastapi import APIRouter, WebSocket

from app.deps import get_lock, get_service
from app.routers.operator import MAX_MESSAGE_BYTES, receive_message, ws_client
from app.service import ServiceError
from app.state import with_operator_lock

log = logging.getLogger(__name__)
router = APIRouter(tags=["state"])

RATE_RANGE_HZ = (1.0, 50.0)  # [Hz] the robot publishes at 50 Hz: faster would repeat documents
DEFAULT_RATE_HZ = 10.0
UNAVAILABLE_RETRY_S = 0.5  # [s] while the robot process is down, how often the stream says so


def _error(detail: str, field: str | None = None) -> str:
    return json.dumps({k: v for k, v in {"ok": False, "detail": detail, "field": field}.items() if v is not None})


def check_rate(value: object) -> float:
    """A rate [Hz] in RATE_RANGE_HZ, or ValueError saying what is allowed."""
    lo, hi = RATE_RANGE_HZ
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise ValueError(f"rate_hz: {value!r} is not a number; give {lo:g} to {hi:g} [Hz]") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"rate_hz: {value!r} is not a number; give {lo:g} to {hi:g} [Hz]")
    if not lo <= value <= hi:
        raise ValueError(f"rate_hz: {value:g} Hz is outside the allowed range [{lo:g}, {hi:g}] Hz")
    return float(value)


def _rate_message(text: str) -> float:
    """The rate of a {"rate_hz": N} message, or ValueError naming the field."""
    try:
        msg = json.loads(text)
    except ValueError as exc:
        raise ValueError(f"body: invalid JSON ({exc})") from None
    if not isinstance(msg, dict):
        raise ValueError("body: send a JSON object {\"rate_hz\": N}")
    unknown = sorted(set(msg) - {"rate_hz"})
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown field; the only one is rate_hz")
    if "rate_hz" not in msg:
        raise ValueError("rate_hz: field required")
    return check_rate(msg["rate_hz"])


@router.websocket("/ws/telemetry")
async def telemetry_stream(ws: WebSocket) -> None:
    """`?rate_hz=N` (1-50, default 10): the /api/state document as a JSON text message N times a second
    (a new one each time the robot has published since; none while it has not). `?client=<id>`: this
    connection keeps its client's operator lock. While the robot process is down: {"ok": false, "detail"}
    twice a second. Client messages: {"rate_hz": N}; an invalid one is answered {"ok": false, "detail",
    "field"} and the stream goes on."""
    lock = get_lock(ws)
    client, bad_client = ws_client(ws)
    await ws.accept()
    try:
        rate = check_rate(ws.query_params.get("rate_hz", DEFAULT_RATE_HZ))
        if bad_client is not None:
            raise ValueError(bad_client)
    except ValueError as exc:
        await ws.send_text(_error(str(exc), field=str(exc).split(":", 1)[0]))
        await ws.close(code=1008, reason=str(exc)[:120])
        return
    if client is not None:
        lock.connected(client)
    period = [1.0 / rate]
    send_lock = asyncio.Lock()

    async def send(text: str) -> None:
        async with send_lock:
            await ws.send_text(text)

    async def reader() -> None:
        while True:
            text = await receive_message(ws)
            if text is None:
                return
            if len(text) > MAX_MESSAGE_BYTES:
                await send(_error(f"body: message of {len(text)} bytes; the limit is {MAX_MESSAGE_BYTES}", "body"))
                continue
            if not text:
                await send(_error("body: send {\"rate_hz\": N} as a JSON text message", "body"))
                continue
            try:
                period[0] = 1.0 / _rate_message(text)
            except ValueError as exc:
                await send(_error(str(exc), field=str(exc).split(":", 1)[0]))
                continue
            await send(json.dumps({"ok": True, "rate_hz": round(1.0 / period[0], 6)}))

    reading = asyncio.create_task(reader())
    try:
        last = None
        due = time.monotonic()
        while not reading.done():
            try:
                service = get_service(ws)
                body = service.state_json()
            except ServiceError as exc:
                await send(_error(str(exc)))
                last = None
                await asyncio.wait({reading}, timeout=UNAVAILABLE_RETRY_S)
                continue
            if body is not last:
                last = body
                await send(with_operator_lock(body, lock).decode())
            due += period[0]
            now = time.monotonic()
            if due < now - period[0]:  # fell behind (a slow client): no burst to catch up
                due = now
            await asyncio.wait({reading}, timeout=max(0.0, due - now))
    except Exception as exc:  # noqa: BLE001 - the client left while we were sending
        log.debug("telemetry stream ended: %s", exc)
    finally:
        reading.cancel()
        if client is not None:
            lock.disconnected(client)
