"""The operator's camera view and the recognitions over it ([OP] V-A, II): one JPEG frame of the wide head
camera, a WebSocket stream of them, the recognitions the behaviours remember, and the operator's confirmation or
correction of one (what later behaviours use)."""

from __future__ import annotations

import json
import logging
import math
import time
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Body, Path, WebSocket
from fastapi.responses import Response
from pydantic import BaseModel, Field

from app.console.deps import ServiceDep, get_service
from app.console.errors import errors
from app.console.schemas import StrictBody
from app.console.ws import RateStream, check_rate, error_text
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
    return check_rate(value, STREAM_RATE_HZ)


@router.websocket("/ws/camera")
async def camera_stream(ws: WebSocket) -> None:
    """`?rate_hz=N` (1-15, default 10): each new frame of the wide head camera as two messages, a JSON text
    {"ok": true, "camera", "seq", "time_s", "width", "height", "recognitions": [...]} (each recognition with its
    image box "box_px" [u0, v0, u1, v1] in this view, null when out of view) and then the JPEG as a binary
    message. The console renders while at least one client watches, at the highest rate asked. `?client=<id>`
    keeps its operator lock. Client messages: {"rate_hz": N} or {"ping": X} (answered {"pong": X}); an invalid
    one is answered with an error naming the field."""
    stream = await RateStream.open(ws, STREAM_RATE_HZ, DEFAULT_STREAM_RATE_HZ)
    if stream is None:
        return
    try:
        last = None
        sent_at = -math.inf
        while not stream.reading.done():
            try:
                service = get_service(ws)
                service.published()
                frame = service.latest_camera_frame(1.0 / stream.period_s)
            except ServiceError as exc:
                await stream.send(error_text(str(exc)))
                await stream.wait(UNAVAILABLE_RETRY_S)
                continue
            now = time.monotonic()
            # a new frame once the period is (nearly) over: looked for every POLL_S, so that a stream at the feed's
            # own rate does not alias with it and skip frames
            if frame is not None and frame is not last and now - sent_at >= 0.9 * stream.period_s:
                last, sent_at = frame, now
                async with stream.send_lock:
                    await ws.send_text(json.dumps({"ok": True, **frame.meta()}))
                    await ws.send_bytes(frame.jpeg)
            # nothing may be sent before 0.9 period after the last frame: sleep until then, then look every POLL_S
            await stream.wait(max(POLL_S, sent_at + 0.9 * stream.period_s - time.monotonic()))
    except Exception as exc:  # noqa: BLE001 - the client left while we were sending
        log.debug("camera stream ended: %s", exc)
    finally:
        stream.close()


# ---- the recognitions ----------------------------------------------------------------------------------------
class RecognitionsState(BaseModel):
    recognitions: dict[str, dict[str, Any]] = Field(
        description="object -> its latest recognition as the behaviours recall it: position_m (world) [m], "
                    "sigma_m [m], yaw_deg, bbox_px (the narrow camera's image region), time_s; after the operator: "
                    "status 'confirmed' or 'corrected' and estimated_position_m (the robot's own)")


class ConfirmRequest(StrictBody):
    status: Literal["confirmed"] = Field(default="confirmed", description="the operator saw it where the robot says")


class CorrectRequest(StrictBody):
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
