"""The operator's camera view and the recognitions over it ([OP] V-A, II): one JPEG frame of the wide head
camera, a WebSocket stream of them, the recognitions the behaviours remember, and the operator's confirmation or
correction of one (what later behaviours use)."""

from __future__ import annotations

import asyncio
import json
import logging
import math
import time
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Body, Path, WebSocket
from fastapi.responses import Response
from pydantic import BaseModel, Field

from app.deps import ServiceDep, get_lock, get_service
from app.errors import errors
from app.routers.operator import MAX_MESSAGE_BYTES, receive_message, ws_client
from app.schemas import _Body
from app.service import ServiceError
from app.service.camera_feed import VIEW_CAMERA, VIEW_RATE_HZ
from app.service.verbs import MAX_POSITION_M

log = logging.getLogger(__name__)
router = APIRouter(tags=["camera"])

STREAM_RATE_HZ = (1.0, VIEW_RATE_HZ)  # [Hz] the feed renders at most VIEW_RATE_HZ
DEFAULT_STREAM_RATE_HZ = 10.0
UNAVAILABLE_RETRY_S = 0.5
POLL_S = 0.01  # [s] how often a stream looks for a new frame
Coordinate = Annotated[float, Field(ge=-MAX_POSITION_M, le=MAX_POSITION_M)]
ObjectName = Annotated[str, Path(max_length=64, pattern=r"^[a-z_]+$",
                                 description="the recognised object, e.g. can, trash_box")]


@router.get(f"/api/camera/{VIEW_CAMERA}.jpg", response_class=Response,
            responses={200: {"content": {"image/jpeg": {}},
                             "description": "a JPEG of the wide head camera (320 x 240 px, 93.6 x 70.8 deg) rendered "
                                            "within the last 0.5 s; headers X-Frame-Seq, X-Frame-Time (control "
                                            "time [s]), X-Frame-Size (W x H px)"}, **errors()},
            summary="One frame of the wide head camera (rendering starts on request and stops 2 s after the last)")
def camera_frame(service: ServiceDep) -> Response:
    frame = service.camera_frame()
    return Response(content=frame.jpeg, media_type="image/jpeg",
                    headers={"X-Frame-Seq": str(frame.seq), "X-Frame-Time": f"{frame.time_s:.4f}",
                             "X-Frame-Size": f"{frame.width}x{frame.height}", "Cache-Control": "no-store"})


def check_stream_rate(value: object) -> float:
    lo, hi = STREAM_RATE_HZ
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


def _error(detail: str, field: str | None = None) -> str:
    return json.dumps({k: v for k, v in {"ok": False, "detail": detail, "field": field}.items() if v is not None})


def _rate_message(text: str) -> float:
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
    return check_stream_rate(msg["rate_hz"])


@router.websocket("/ws/camera")
async def camera_stream(ws: WebSocket) -> None:
    """`?rate_hz=N` (1-15, default 10): each new frame of the wide head camera as two messages, a JSON text
    {"ok": true, "camera", "seq", "time_s", "width", "height", "recognitions": [...]} (each recognition with its
    image box "box_px" [u0, v0, u1, v1] in this view, null when out of view) and then the JPEG as a binary
    message. The console renders while at least one client watches, at the highest rate asked. `?client=<id>`
    keeps its operator lock. Client messages: {"rate_hz": N}; an invalid one is answered with an error naming
    the field."""
    lock = get_lock(ws)
    client, bad_client = ws_client(ws)
    await ws.accept()
    try:
        rate = check_stream_rate(ws.query_params.get("rate_hz", DEFAULT_STREAM_RATE_HZ))
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

    async def send_text(text: str) -> None:
        async with send_lock:
            await ws.send_text(text)

    async def reader() -> None:
        while True:
            text = await receive_message(ws)
            if text is None:
                return
            if len(text) > MAX_MESSAGE_BYTES:
                await send_text(_error(f"body: message of {len(text)} bytes; the limit is {MAX_MESSAGE_BYTES}",
                                       "body"))
                continue
            try:
                period[0] = 1.0 / _rate_message(text or "null")
            except ValueError as exc:
                await send_text(_error(str(exc), field=str(exc).split(":", 1)[0]))
                continue
            await send_text(json.dumps({"ok": True, "rate_hz": round(1.0 / period[0], 6)}))

    reading = asyncio.create_task(reader())
    try:
        last = None
        sent_at = -math.inf
        while not reading.done():
            try:
                service = get_service(ws)
                service.published()
                frame = service.latest_camera_frame(1.0 / period[0])
            except ServiceError as exc:
                await send_text(_error(str(exc)))
                await asyncio.wait({reading}, timeout=UNAVAILABLE_RETRY_S)
                continue
            now = time.monotonic()
            # a new frame once the period is (nearly) over: looked for every POLL_S, so that a stream at the feed's
            # own rate does not alias with it and skip frames
            if frame is not None and frame is not last and now - sent_at >= 0.9 * period[0]:
                last, sent_at = frame, now
                async with send_lock:
                    await ws.send_text(json.dumps({"ok": True, **frame.meta()}))
                    await ws.send_bytes(frame.jpeg)
            # nothing may be sent before 0.9 period after the last frame: sleep until then, then look every POLL_S
            await asyncio.wait({reading}, timeout=max(POLL_S, sent_at + 0.9 * period[0] - time.monotonic()))
    except Exception as exc:  # noqa: BLE001 - the client left while we were sending
        log.debug("camera stream ended: %s", exc)
    finally:
        reading.cancel()
        if client is not None:
            lock.disconnected(client)


# ---- the recognitions ----------------------------------------------------------------------------------------
class RecognitionsState(BaseModel):
    recognitions: dict[str, dict[str, Any]] = Field(
        description="object -> its latest recognition as the behaviours recall it: position_m (world) [m], "
                    "sigma_m [m], yaw_deg, bbox_px (the narrow camera's image region), time_s; after the operator: "
                    "status 'confirmed' or 'corrected' and estimated_position_m (the robot's own)")


class ConfirmRequest(_Body):
    status: Literal["confirmed"] = Field(default="confirmed", description="the operator saw it where the robot says")


class CorrectRequest(_Body):
    position_m: list[Coordinate] = Field(min_length=3, max_length=3, examples=[[1.2, 0.0, 0.75]],
                                         description=f"[x, y, z] world frame [m], |each| <= {MAX_POSITION_M:g}: where "
                                                     "the object really is (later behaviours use it)")


class RecognitionAnswer(BaseModel):
    ok: bool = True
    message: str
    recognition: dict[str, Any]


@router.get("/api/recognitions", response_model=RecognitionsState, responses=errors(),
            summary="The latest recognition of each object (what later behaviours use)")
def recognitions(service: ServiceDep) -> RecognitionsState:
    return RecognitionsState(recognitions=service.recognitions())


@router.post("/api/recognitions/{name}/confirm", response_model=RecognitionAnswer,
             responses=errors(404, 422, e404="no recognition of that object yet (the recognised ones are listed)"),
             summary="Confirm the robot's latest recognition of an object ([OP] II: the human confirms)")
def confirm(name: ObjectName, service: ServiceDep,
            req: Annotated[ConfirmRequest | None, Body()] = None) -> RecognitionAnswer:
    rec = service.confirm_recognition(name)
    return RecognitionAnswer(message=f"{name} confirmed at {_xyz(rec['position_m'])} m", recognition=rec)


@router.post("/api/recognitions/{name}/correct", response_model=RecognitionAnswer,
             responses=errors(404, 422, e404="no recognition of that object yet (the recognised ones are listed)"),
             summary="Correct the position of an object the robot recognised: later behaviours use the correction")
def correct(name: ObjectName, req: CorrectRequest, service: ServiceDep) -> RecognitionAnswer:
    rec = service.confirm_recognition(name, req.position_m)
    return RecognitionAnswer(message=f"{name} corrected to {_xyz(rec['position_m'])} m (estimated "
                                     f"{_xyz(rec['estimated_position_m'])} m)", recognition=rec)


def _xyz(p) -> str:
    return "(" + ", ".join(f"{float(v):.3f}" for v in p) + ")"
