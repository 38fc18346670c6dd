"""The operator's emergency stops: the hard e-stop (hrpsys HardEmergencyStopper service), the motion stop and
the EmergencyStopper's parameters (hrpsys EmergencyStopperService)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Body

from app.deps import ServiceDep
from app.errors import errors
from app.hot_paths import estop_reply
from app.routers.params import changes_json_schema, params_document
from app.schemas import EstopResponse, Ok
from app.service import InvalidArgument

router = APIRouter(prefix="/api/estop", tags=["emergency"])


@router.post("", response_model=EstopResponse, responses=errors(),
             summary="Engage the hard e-stop: freeze the joint command now; everything upstream holds (walking "
                     "stops in place, the sequence stops). Any page may send it, with or without a body.")
async def engage(service: ServiceDep) -> EstopResponse:
    # on the event loop itself (no thread-pool hop that other requests could fill), through the robot's own
    # e-stop pipe; it answers once the loop has engaged it (a millisecond or so)
    # (app.hot_paths answers this path before FastAPI does; this route documents it and answers its errors)
    return EstopResponse(**estop_reply(service.estop()))


@router.post("/release", response_model=Ok, responses=errors(409),
             summary="Release the hard e-stop (blends to where the robot is) and clear the fault; refused after "
                     "a fall (reset instead)")
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


# ---- EmergencyStopper parameters: one view over the layers that own them ---------------------------------

#: presented name -> (owning chain layer, field of that layer's Params dataclass). The revert timing lives in
#: the EmergencyStopper's params, the capture-point flag that triggers it in the Stabilizer's.
ES_PARAMS: dict[str, tuple[str, str]] = {
    "t1": ("es", "t1_s"),
    "t2": ("es", "t2_s"),
    "recover_time": ("es", "recover_time_s"),
    "cp_threshold_m": ("st", "cp_threshold_m"),
    "mode": ("st", "emergency_mode"),
}
#: deprecated presented name -> the name it stands for (accepted in changes, also given in the document)
ES_DEPRECATED: dict[str, str] = {"threshold": "cp_threshold_m"}

EsChangesBody = Annotated[dict[str, Any], Body(
    description="{parameter name: new value} for some of " + ", ".join(ES_PARAMS) + ", e.g. {\"t1\": 0.8}")]


def es_changes(changes: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """{owner: {field: value}} from the presented names (unknown names -> 422 listing the valid ones)."""
    if not changes:
        raise InvalidArgument("body", f"give at least one parameter; valid: {list(ES_PARAMS)}")
    unknown = sorted(set(changes) - set(ES_PARAMS) - set(ES_DEPRECATED))
    if unknown:
        raise InvalidArgument(unknown[0], f"unknown parameter(s) {unknown}; valid: {list(ES_PARAMS)}")
    for old, name in ES_DEPRECATED.items():
        if old in changes and name in changes:  # (the schema says so too: not both)
            raise InvalidArgument(old, f"{old!r} is the deprecated name of {name!r}: give one of them")
    grouped: dict[str, dict[str, Any]] = {}
    for name, value in changes.items():
        layer, field = ES_PARAMS[ES_DEPRECATED.get(name, name)]
        grouped.setdefault(layer, {})[field] = value
    return grouped


def es_document(params: dict) -> dict[str, Any]:
    """{"params": {name: value}, "schema": [...]} in the presented names, from the owners' declarations."""
    docs = {layer: params_document(p) for layer, p in params.items()}
    values, schema = {}, []
    for name, (layer, field) in ES_PARAMS.items():
        values[name] = docs[layer]["params"][field]
        declared = next(d for d in docs[layer]["schema"] if d["name"] == field)
        schema.append({**declared, "name": name, "layer": layer, "param": f"{type(params[layer]).__name__}.{field}"})
    for old, name in ES_DEPRECATED.items():
        values[old] = values[name]
    return {"params": values, "schema": schema}


params_router = APIRouter(prefix="/api/emergency-stopper", tags=["emergency"])


@params_router.get("/params", responses=errors(404),
                   summary="EmergencyStopper parameters: T1, T2, recover time [s] and the Stabilizer's "
                           "capture-point flag (cp_threshold_m [m], mode), with units, defaults and ranges")
def get_es_params(service: ServiceDep) -> dict[str, Any]:
    return es_document(service.params("es", "st"))


def es_changes_schema() -> dict[str, Any]:
    """The JSON schema of some EmergencyStopper parameters in the presented names (the PUT's body, and an
    experiment's `params`), from the owning layers' declarations."""
    from controller.core.system import layer_params_classes

    classes = layer_params_classes()
    schema = changes_json_schema({name: (classes[layer], field) for name, (layer, field) in ES_PARAMS.items()},
                                 "EmergencyStopperChanges")
    for old, name in ES_DEPRECATED.items():
        schema["properties"][old] = {**schema["properties"][name], "deprecated": True,
                                     "description": f"deprecated name of {name}"}
        schema.setdefault("allOf", []).append({"not": {"required": [old, name]}})
    return schema


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

