"""The operator's emergency stops: the hard e-stop (hrpsys HardEmergencyStopper service), the motion stop and
the EmergencyStopper's parameters (hrpsys EmergencyStopperService)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Header
from fastapi.responses import JSONResponse

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.params_http import ES_PARAMS, EsChangesBody, es_changes, es_changes_schema, es_document
from app.console.schemas import EstopResponse, Ok
from app.service import InvalidArgument
from app.service.estop import COPY_WINDOW_S

router = APIRouter(prefix="/api/estop", tags=["emergency"])


@router.post("", response_model=EstopResponse, responses=errors(409),
             summary="Engage the hard e-stop: freeze the joint command now (in a swing: land the step, then "
                     "freeze); everything upstream holds. Any page may send it, with or without a body. Answered "
                     "200 only when the loop has it engaged; 409 `late_copy` for a copy of a press already released")
async def engage(service: ServiceDep, x_estop_press: Annotated[str | None, Header(
        description="this press's id (1-64 of A-Z a-z 0-9 _ . : -), the same on each way the page sends it (its "
        "e-stop door, its stick stream, this POST): a copy arriving after that press was released, within "
        f"{COPY_WINDOW_S:g} s of its first copy, engages nothing (409 late_copy); any other press engages. A "
        "malformed id is ignored (the stop engages, press_ignored says why)")] = None) -> Any:
    # on the event loop itself (no thread-pool hop that other requests could fill), through the robot's own
    # e-stop pipe; it answers once the loop has handled it (a millisecond or so)
    # (app.console.hot_paths answers this path before FastAPI does; this route documents it and answers its errors)
    ack = service.estop(x_estop_press)
    return JSONResponse(ack.reply(), status_code=200 if ack.engaged else 409)


@router.post("/release", response_model=Ok, responses=errors(409),
             summary="Release the hard e-stop (blends to where the robot is) and clear the fault; refused after "
                     "a fall (reset instead), and when a press reached the robot after this release was sent (409 "
                     "hard_stop: that press stays in force)")
def release(service: ServiceDep) -> Ok:
    return Ok(message=service.release_estop())


motion_router = APIRouter(prefix="/api/motion", tags=["emergency"])


@motion_router.post("/stop", response_model=Ok, responses=errors(),
                    summary="Stop and revert the planned motion ([MLC] Eq. 15); balance keeps working")
def stop_motion(service: ServiceDep) -> Ok:
    return Ok(message=service.stop_motion())


@motion_router.post("/release", response_model=Ok, responses=errors(409),
                    summary="Release the motion stop: blend back to the live plan over recover_time_s")
def release_motion(service: ServiceDep) -> Ok:
    return Ok(message=service.release_motion())


# ---- EmergencyStopper parameters (app.console.params_http: the view over the layers that own them) ---------------
params_router = APIRouter(prefix="/api/emergency-stopper", tags=["emergency"])


@params_router.get("/params", responses=errors(404),
                   summary="EmergencyStopper parameters: T1, T2, recover time [s] and the Stabilizer's "
                           "capture-point flag (cp_threshold_m [m], mode), with units, defaults and ranges")
def get_es_params(service: ServiceDep) -> dict[str, Any]:
    return es_document(service.params("es", "st"))


def _es_body() -> dict[str, Any]:
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": es_changes_schema()}}}}


@params_router.put("/params", responses=errors(404, 422), openapi_extra=_es_body(),
                   summary="Change some EmergencyStopper parameters (validated; each owning layer's params "
                           "replaced whole at a tick boundary, all or none)")
def put_es_params(service: ServiceDep, changes: EsChangesBody) -> dict[str, Any]:
    grouped = es_changes(changes)
    try:
        service.set_params(grouped)
    except InvalidArgument as exc:  # name the presented field, not the layer's
        presented = {f"{field}": name for name, (_, field) in ES_PARAMS.items()}
        raise InvalidArgument(presented.get(exc.field, exc.field), exc.message) from None
    return es_document(service.params("es", "st"))

