"""WS /ws/telemetry: the /api/state document pushed at a rate the client chooses (1-50 Hz), for the page and
for scripts. A message {"rate_hz": N} changes the rate, {"ping": X} is echoed {"pong": X}; an invalid one is
answered with an error naming the field, and the stream goes on."""

from __future__ import annotations

import logging
import time

from fastapi import APIRouter, WebSocket

from app.console.deps import get_journal, get_service
from app.console.state import with_console_state
from app.console.ws import RateStream, error_text
from app.console.ws import check_rate as check_stream_rate
from app.service import ServiceError

log = logging.getLogger(__name__)
router = APIRouter(tags=["state"])

RATE_RANGE_HZ = (1.0, 50.0)  # [Hz] the robot publishes at 50 Hz: faster would repeat documents
DEFAULT_RATE_HZ = 10.0
UNAVAILABLE_RETRY_S = 0.5  # [s] while the robot process is down, how often the stream says so


def check_rate(value: object) -> float:
    """A rate [Hz] in RATE_RANGE_HZ, or ValueError saying what is allowed."""
    return check_stream_rate(value, RATE_RANGE_HZ)


@router.websocket("/ws/telemetry")
async def telemetry_stream(ws: WebSocket) -> None:
    """`?rate_hz=N` (1-50, default 10): the /api/state document as a JSON text message N times a second
    (a new one each time the robot has published since; none while it has not). `?client=<id>`: this
    connection keeps its client's operator lock. While the robot process is down: {"ok": false, "detail"}
    twice a second. Client messages: {"rate_hz": N}, or {"ping": X} (a finite number) answered {"pong": X} (the
    page's round trip); an invalid one is answered {"ok": false, "detail", "field"} and the stream goes on."""
    stream = await RateStream.open(ws, RATE_RANGE_HZ, DEFAULT_RATE_HZ)
    if stream is None:
        return
    lock = stream.lock
    journal = get_journal(ws)
    try:
        last = None
        due = time.monotonic()
        while not stream.reading.done():
            try:
                service = get_service(ws)
                body = service.state_json()
            except ServiceError as exc:
                await stream.send(error_text(str(exc)))
                last = None
                await stream.wait(UNAVAILABLE_RETRY_S)
                continue
            if body is not last:
                last = body
                await stream.send(with_console_state(body, lock, journal).decode())
            due += stream.period_s
            now = time.monotonic()
            if due < now - stream.period_s:  # fell behind (a slow client): no burst to catch up
                due = now
            await stream.wait(due - now)
    except Exception as exc:  # noqa: BLE001 - the client left while we were sending
        log.debug("telemetry stream ended: %s", exc)
    finally:
        stream.close()
