"""The operator's velocities at the operational points ([OP] II-III, Eq. 5's xi_motion): one PUT per setpoint
or a WebSocket stream of them at up to 50 Hz, each acknowledged with the control tick it reached; and the
operation layer's parameters. Twists are in the feet frame F (controller.operation.points): linear [m/s],
angular [deg/s]."""

from __future__ import annotations

import asyncio
import json
import math
import time
from typing import Annotated, Any

from fastapi import APIRouter, Body, Header, WebSocket, WebSocketDisconnect
from pydantic import TypeAdapter, ValidationError

from app.deps import LockDep, ServiceDep, get_service
from app.deps import get_lock as lock_of
from app.errors import errors
from app.operator_lock import Locked
from app.params_http import params_changes_body, params_document
from app.schemas import LockRequest, OperatorAck, OperatorLockState, OperatorVelocityRequest
from app.service import ServiceError, estop, ignored_message
from app.service.setpoints import Setpoint, SetpointAck
from app.state import jsonable
from app.ws import MAX_MESSAGE_BYTES, receive_message, ws_client

router = APIRouter(prefix="/api/operator", tags=["operator"])
ws_router = APIRouter(tags=["operator"])

ACK_POLL_S = 0.003  # [s] how often the stream looks for the robot's acknowledgements
ACK_GIVE_UP_S = 1.0  # [s] a setpoint not acknowledged by then is answered with an error


def setpoint_of(req: OperatorVelocityRequest) -> Setpoint:
    """The request in SI units (deg/s -> rad/s), checked once more by Setpoint itself."""
    return Setpoint(req.point, tuple(float(v) for v in req.linear), tuple(math.radians(v) for v in req.angular),
                    getattr(req, "max_stride", None), getattr(req, "foot_distance", None))


async def _estop_message(text: str, service, send) -> bool:
    """An e-stop on the stream (app.service.estop.parse_text: any JSON object whose "estop" is true): the hard
    e-stop, as POST /api/estop (never refused by the operator lock), answered with its reply and `"estop": true`;
    the page's open socket is a faster way in than a new request. False: not an e-stop."""
    request = estop.parse_text(text)
    if request is None:
        return False
    try:
        reply = service.estop(request).reply()
    except ServiceError as exc:
        await send(_error(str(exc), reason=getattr(exc, "reason", None), estop=True))
        return True
    await send(json.dumps({**reply, "estop": True}))
    return True


def _stop_points(service, points) -> None:
    """A zero setpoint for each of `points`: a stream that ends (closed, dropped) stops what it moved at the next
    tick instead of after the dead-man's 200 ms + 100 ms ramp."""
    for point in points:
        try:
            service.put_setpoint(Setpoint(point, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
        except ServiceError:
            pass  # the e-stop or a fall already holds it, or the robot process is gone: nothing moves


def ack_body(ack: SetpointAck, seq: int) -> dict[str, Any]:
    return {"ok": True, "point": ack.point, "seq": seq, "applied_seq": ack.seq, "tick": ack.tick,
            "time_s": ack.time_s}


@router.put("/velocity", response_model=OperatorAck, responses=errors(404, 409, 422, e404="the chain has no "
            "operation layer"),
            summary="The operator's velocity of one operational point (feet frame F: linear [m/s], angular "
                    "[deg/s]; walk: linear (vx, vy, 0), angular (0, 0, vtheta) and the step parameters). A "
                    "setpoint older than 200 ms counts as zero (ramped down over 100 ms): stream it (WS "
                    "/ws/operator) to keep moving. Answers with the control tick it reached.")
def put_velocity(req: OperatorVelocityRequest, service: ServiceDep) -> OperatorAck:
    sp = setpoint_of(req)
    ack = service.operator_velocity(sp)
    return OperatorAck(**ack_body(ack, ack.seq))


def _operation_params_class():
    from controller.core.system import layer_params_classes

    return layer_params_classes().get("op")


_OP_PARAMS = _operation_params_class()


@router.get("/params", responses=errors(404),
            summary="The operation layer's parameters (per-point speed limits, dead-man, ...) and their schema")
def get_params(service: ServiceDep) -> dict[str, Any]:
    return params_document(service.params("op")["op"])


@router.put("/params", responses=errors(404, 422),
            openapi_extra=params_changes_body(_OP_PARAMS) if _OP_PARAMS is not None else None,
            summary="Replace some of the operation layer's parameters (all or none, at one tick boundary)")
def put_params(service: ServiceDep,
               changes: Annotated[dict[str, Any], Body(description="{field: value}")]) -> dict[str, Any]:
    new = service.set_params({"op": changes})
    return params_document(new["op"])


# ---- the operator lock (app.operator_lock) ------------------------------------------------------------------
@router.get("/lock", response_model=OperatorLockState, responses=errors(),
            summary="Who holds the operator lock (null: nobody; any client may control)")
def lock_state(lock: LockDep) -> OperatorLockState:
    return OperatorLockState(**lock.state().to_dict())


@router.post("/lock", response_model=OperatorLockState, responses=errors(422, 423),
             summary="Take the operator lock (or renew it): the others' control requests are then answered 423 "
                     "naming the holder, except the e-stop and the motion stop. Kept while the holder has a "
                     "WebSocket open with ?client=<id>, else for lease_s after its last request; grace_s after "
                     "its last WebSocket closed")
def take_lock(req: LockRequest, lock: LockDep) -> OperatorLockState:
    return OperatorLockState(**lock.take(req.client).to_dict())


@router.delete("/lock", response_model=OperatorLockState, responses=errors(422, 423),
               summary="Give the operator lock back (the holder only, named by its X-Client-Id header)")
def release_lock(lock: LockDep, x_client_id: Annotated[str | None, Header(
        pattern=r"^[A-Za-z0-9._:-]{1,64}$", description="the holder's client id")] = None) -> OperatorLockState:
    lock.release(x_client_id)
    return OperatorLockState(**lock.state().to_dict())


_REQUEST = TypeAdapter(OperatorVelocityRequest)


def _error(detail: str, field: str | None = None, reason: str | None = None, seq: int | None = None,
           **extra: Any) -> str:
    return json.dumps({k: v for k, v in {"ok": False, "detail": detail, "field": field, "reason": reason,
                                         "seq": seq, **extra}.items() if v is not None})


@ws_router.websocket("/ws/operator")
async def operator_stream(ws: WebSocket) -> None:
    """Setpoints as JSON text messages, each the body of PUT /api/operator/velocity; every message is
    answered with {"ok": true, "point", "seq", "applied_seq", "tick", "time_s"} once the robot has applied
    it (or a newer setpoint of the same point), or {"ok": false, "detail", "field"?, "reason"?}: a setpoint
    the robot ignored (the hard e-stop) says {"ok": false, "ignored": true, "reason": "hard_stop" or
    "before_release", ...}; one refused by the operator lock {"reason": "locked", "holder"}. The message
    {"estop": true} engages the hard e-stop (POST /api/estop's answer with "estop": true; any client, the lock
    never refuses it); {"estop": true, "press": "<id>"} with the press's id, as POST /api/estop's X-Estop-Press.
    `?client=<id>`:
    this connection keeps its client's operator lock (app.operator_lock)."""
    try:
        service = get_service(ws)
    except ServiceError as exc:
        await ws.close(code=1011, reason=str(exc)[:120])
        return
    op_lock = lock_of(ws)
    client, bad_client = ws_client(ws)
    await ws.accept()
    if bad_client is not None:
        await ws.send_text(_error(bad_client, field="client"))
        await ws.close(code=1008, reason="invalid client id")
        return
    if client is not None:
        op_lock.connected(client)
    pending: list[tuple[str, int, float]] = []  # (point, seq, monotonic time put)
    lock = asyncio.Lock()

    async def send(text: str) -> None:
        async with lock:
            await ws.send_text(text)

    async def acker() -> None:
        while True:
            await asyncio.sleep(ACK_POLL_S)
            if not pending:
                continue
            now = time.monotonic()
            try:
                acks = service.published().setpoint_acks
            except ServiceError as exc:
                while pending:
                    point, seq, _ = pending.pop(0)
                    await send(_error(str(exc), seq=seq))
                continue
            still = []
            for point, seq, put_at in pending:
                ack = acks.get(point)
                if ack is not None and ack.seq == seq and ack.ignored is not None:
                    await send(_error(ignored_message(ack.ignored), reason=ack.ignored, seq=seq, ignored=True,
                                      point=point, tick=ack.tick, time_s=ack.time_s))
                elif ack is not None and ack.seq >= seq:
                    await send(json.dumps(jsonable(ack_body(ack, seq))))
                elif now - put_at > ACK_GIVE_UP_S:
                    await send(_error(f"the robot did not acknowledge setpoint {seq} within {ACK_GIVE_UP_S:g} s",
                                      seq=seq))
                else:
                    still.append((point, seq, put_at))
            pending[:] = still

    task = asyncio.create_task(acker())
    streamed: set[str] = set()  # the points this stream moved: zeroed at once when it ends
    try:
        while True:
            text = await receive_message(ws)
            if text is None:
                break
            if not text:
                await send(_error("body: send each setpoint as a JSON text message", field="body"))
                continue
            if len(text) > MAX_MESSAGE_BYTES:
                await send(_error(f"message of {len(text)} bytes; the limit is {MAX_MESSAGE_BYTES}", field="body"))
                continue
            if await _estop_message(text, service, send):
                continue
            try:
                req = _REQUEST.validate_json(text)
            except ValidationError as exc:
                err = exc.errors()[0]
                field = ".".join(str(p) for p in err.get("loc", ()) if "[" not in str(p)) or "body"
                await send(_error(f"{field}: {err.get('msg', 'invalid')}", field=field))
                continue
            try:
                op_lock.check(client, "the stick stream")
            except Locked as exc:
                await send(_error(str(exc), reason="locked", holder=exc.holder))
                continue
            try:
                numbered = service.put_setpoint(setpoint_of(req))
            except ServiceError as exc:
                reason = getattr(exc, "reason", None)
                await send(_error(str(exc), field=getattr(exc, "field", None), reason=reason,
                                  ignored=True if reason in ("hard_stop", "fallen") else None))
                continue
            pending.append((numbered.point, numbered.seq, time.monotonic()))
            streamed.add(numbered.point)
    except WebSocketDisconnect:
        pass
    finally:
        task.cancel()
        _stop_points(service, streamed)
        if client is not None:
            op_lock.disconnected(client)
