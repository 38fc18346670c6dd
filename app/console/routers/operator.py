"""The operator's velocities at the operational points ([OP] II-III, Eq. 5's xi_motion): one PUT per setpoint
or a WebSocket stream of them at up to 50 Hz, each acknowledged with the control tick it reached; and the
operation layer's parameters. Twists are in the feet frame F (controller.operation.points): linear [m/s],
angular [deg/s]."""

from __future__ import annotations

import asyncio
import itertools
import json
import math
import time
from typing import Annotated, Any

from fastapi import APIRouter, Body, Header, Request, WebSocket, WebSocketDisconnect
from pydantic import TypeAdapter, ValidationError

from app.console.command_journal import client_name
from app.console.deps import LockDep, ServiceDep, get_service
from app.console.deps import get_lock as lock_of
from app.console.errors import errors
from app.console.operator_lock import Locked
from app.console.params_http import params_changes_body, params_document
from app.console.schemas import LockRequest, OperatorAck, OperatorLockLease, OperatorLockState, OperatorVelocityRequest
from app.console.state import jsonable
from app.console.ws import MAX_MESSAGE_BYTES, receive_message, ws_client, ws_lock_token, ws_sender_name
from app.service import PointTaken, Refused, Sender, ServiceError, Superseded, estop
from app.service.setpoints import Setpoint, SetpointAck

router = APIRouter(prefix="/api/operator", tags=["operator"])
ws_router = APIRouter(tags=["operator"])

ACK_POLL_S = 0.003  # [s] how often the stream looks for the robot's acknowledgements
ACK_GIVE_UP_S = 1.0  # [s] a setpoint not acknowledged by then is answered with an error
LOCK_TOKEN_DOC = ("the operator lock's lease token (POST /api/operator/lock answers it to the taker only); needed "
                  "while the lock is held")


def setpoint_of(req: OperatorVelocityRequest) -> Setpoint:
    """The request in SI units (deg/s -> rad/s); its schema checked it (the operation layer checks it last)."""
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


def _stop_points(service, points, sender: Sender) -> None:
    """A zero setpoint for each of `points`: a stream that ends (closed, dropped) stops what it moved at the next
    tick instead of after the dead-man's 200 ms + 100 ms ramp; a point another client streams to now is left to
    it. Then the points are free for the others."""
    for point in points:
        try:
            service.put_setpoint(Setpoint(point, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), sender)
        except ServiceError:
            pass  # another client streams to it, the e-stop or a fall holds it, or the robot process is gone
    if sender.stream is not None:
        service.end_stream(sender.stream)


def ack_body(ack: SetpointAck, seq: int) -> dict[str, Any]:
    return {"ok": True, "point": ack.point, "seq": seq, "applied_seq": ack.seq, "tick": ack.tick,
            "time_s": ack.time_s}


@router.put("/velocity", response_model=OperatorAck, responses=errors(
    404, 409, 422, e404="the chain has no operation layer",
    e409="not applied, `reason` says why: hard_stop, before_release (the robot ignored it: the hard e-stop), "
         "fallen; point_taken (another client streams to the point: `owner` names it, first come until its "
         "stream stops); superseded (another client's newer setpoint was applied instead: `by` names it)"),
            summary="The operator's velocity of one operational point (feet frame F: linear [m/s], angular "
                    "[deg/s]; walk: linear (vx, vy, 0), angular (0, 0, vtheta) and the step parameters). A "
                    "setpoint older than 200 ms counts as zero (ramped down over 100 ms): stream it (WS "
                    "/ws/operator) to keep moving. Answers with the control tick it reached, only once it (or a "
                    "newer setpoint of the same client) reached the operation layer. X-Client-Id names the "
                    "client (display only); while the operator lock is held, X-Lock-Token must be its lease.")
def put_velocity(req: OperatorVelocityRequest, service: ServiceDep, lock: LockDep, request: Request,
                 x_client_id: Annotated[str | None, Header(description="this client's display name (the other "
                                                           "clients are told it); default anonymous@<address>")]
                 = None,
                 x_lock_token: Annotated[str | None, Header(description=LOCK_TOKEN_DOC)] = None) -> OperatorAck:
    del x_client_id  # read with the journal's rule (client_name): here for the schema
    sender = Sender(client_name(request.scope))
    numbered = service.put_setpoint(setpoint_of(req), sender, override=lock.holds(x_lock_token))
    ack = service.wait_setpoint(numbered, sender)
    return OperatorAck(**ack_body(ack, numbered.seq))


def _operation_params_class():
    from controller.system import layer_params_classes

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


# ---- the operator lock (app.console.operator_lock) ------------------------------------------------------------------
@router.get("/lock", response_model=OperatorLockState, responses=errors(),
            summary="Who holds the operator lock (null: nobody; any client may control)")
def lock_state(lock: LockDep) -> OperatorLockState:
    return OperatorLockState(**lock.state().to_dict())


@router.post("/lock", response_model=OperatorLockLease, responses=errors(422, 423),
             summary="Take the operator lock (or renew it, with X-Lock-Token): answers a secret lease token, "
                     "to the taker only. Control requests without it (header X-Lock-Token; WebSockets "
                     "?lock_token=) are then answered 423 naming the holder, except the e-stop and the motion "
                     "stop; `client` is only the name the others see. Kept while the holder has a WebSocket open "
                     "with ?lock_token=, else for lease_s after its last request; grace_s after its last "
                     "WebSocket closed")
def take_lock(req: LockRequest, lock: LockDep, x_lock_token: Annotated[str | None, Header(
        description="the lease token, to renew the lock (taking a free lock needs none)")] = None
              ) -> OperatorLockLease:
    state, token = lock.take(req.client, x_lock_token)
    return OperatorLockLease(**state.to_dict(), token=token)


@router.delete("/lock", response_model=OperatorLockState, responses=errors(423),
               summary="Give the operator lock back: the holder only, with its lease token as the X-Lock-Token "
                       "header (423 without it, whatever X-Client-Id says)")
def release_lock(lock: LockDep, x_lock_token: Annotated[str | None, Header(description=LOCK_TOKEN_DOC)] = None
                 ) -> OperatorLockState:
    lock.release(x_lock_token)
    return OperatorLockState(**lock.state().to_dict())


_REQUEST = TypeAdapter(OperatorVelocityRequest)


def _error(detail: str, field: str | None = None, reason: str | None = None, seq: int | None = None,
           **extra: Any) -> str:
    return json.dumps({k: v for k, v in {"ok": False, "detail": detail, "field": field, "reason": reason,
                                         "seq": seq, **extra}.items() if v is not None})


_STREAMS = itertools.count(1)  # each /ws/operator connection's id: two streams are two clients


def _outcome_message(service, numbered: Setpoint, sender: Sender, ack: SetpointAck | None) -> str | None:
    """The stream's answer to `numbered` given the robot's newest ack of its point (None: not yet)."""
    try:
        done = service.setpoint_outcome(numbered, sender, ack)
    except Superseded as exc:
        return _error(str(exc), reason="superseded", seq=numbered.seq, point=numbered.point, by=exc.by,
                      applied_seq=None if ack is None else ack.seq)
    except Refused as exc:  # ignored by the robot (the hard e-stop)
        assert ack is not None
        return _error(str(exc), reason=exc.reason, seq=numbered.seq, ignored=True, point=numbered.point,
                      applied_seq=ack.seq, tick=ack.tick, time_s=ack.time_s)
    return None if done is None else json.dumps(jsonable(ack_body(done, numbered.seq)))


@ws_router.websocket("/ws/operator")
async def operator_stream(ws: WebSocket) -> None:
    """Setpoints as JSON text messages, each the body of PUT /api/operator/velocity; every message is
    answered with {"ok": true, "point", "seq", "applied_seq", "tick", "time_s"} once the robot has applied
    it (or a newer setpoint of the same point from this stream), or {"ok": false, "detail", "field"?,
    "reason"?}: a setpoint the robot ignored (the hard e-stop) says {"ok": false, "ignored": true, "reason":
    "hard_stop" or "before_release", ...}; one refused by the operator lock {"reason": "locked", "holder"};
    one to a point another client streams to {"reason": "point_taken", "field": "point", "owner"} (first come,
    until its stream stops: a zero sent, no setpoint for the dead-man's 0.3 s, or its socket closed); one
    replaced by another client's newer setpoint before the robot applied it {"reason": "superseded", "by"}.
    The message {"estop": true} engages the hard e-stop (POST /api/estop's answer with "estop": true; any
    client, the lock never refuses it); {"estop": true, "press": "<id>"} with the press's id, as POST
    /api/estop's X-Estop-Press. `?client=<name>`: the name the other clients are told (display only);
    `?lock_token=<lease>`: the operator lock's lease token, which makes this the holder's stream (and keeps
    the lock while it is open, app.console.operator_lock)."""
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
    lease_token = ws_lock_token(ws)
    lease = op_lock.connected(lease_token)
    sender = Sender(ws_sender_name(ws, client), next(_STREAMS))
    pending: list[tuple[Setpoint, float]] = []  # (numbered setpoint, monotonic time put)
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
                    numbered, _ = pending.pop(0)
                    await send(_error(str(exc), seq=numbered.seq))
                continue
            still = []
            for numbered, put_at in pending:
                answer = _outcome_message(service, numbered, sender, acks.get(numbered.point))
                if answer is not None:
                    await send(answer)
                elif now - put_at > ACK_GIVE_UP_S:
                    await send(_error(f"the robot did not acknowledge setpoint {numbered.seq} within "
                                      f"{ACK_GIVE_UP_S:g} s", reason="timeout", seq=numbered.seq))
                else:
                    still.append((numbered, put_at))
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
                holder = op_lock.check(lease_token, "the stick stream")
            except Locked as exc:
                await send(_error(str(exc), reason="locked", holder=exc.holder))
                continue
            try:
                numbered = service.put_setpoint(setpoint_of(req), sender, override=holder)
            except PointTaken as exc:
                await send(_error(str(exc), field="point", reason=exc.reason, owner=exc.owner, point=exc.point))
                continue
            except ServiceError as exc:
                reason = getattr(exc, "reason", None)
                await send(_error(str(exc), field=getattr(exc, "field", None), reason=reason,
                                  ignored=True if reason in ("hard_stop", "fallen") else None))
                continue
            pending.append((numbered, time.monotonic()))
            streamed.add(numbered.point)
    except WebSocketDisconnect:
        pass
    finally:
        task.cancel()
        _stop_points(service, streamed, sender)
        op_lock.disconnected(lease)
