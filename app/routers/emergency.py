"""The operator's emergency stops: the hard e-stop (hrpsys HardEmergencyStopper service), the motion stop and
the EmergencyStopper's parameters (hrpsys EmergencyStopperService)."""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any

from fastapi import APIRouter, Body, HTTPException

from app.deps import RuntimeDep
from app.errors import BadRequest
from app.routers.layers import check_types
from app.runtime import jsonable
from app.schemas import Ok
from controller.errors import InvalidCommand

router = APIRouter(prefix="/api/estop", tags=["emergency"])


@router.post("", response_model=Ok, summary="Engage the hard e-stop: freeze the joint command now")
def engage(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    runtime.call(lambda: loop.chain["hes"].engage())
    return Ok(message="hard e-stop engaged")


@router.post("/release", response_model=Ok,
             summary="Release the hard e-stop (blends back to the live command) and clear the fault",
             responses={409: {"description": "the hard e-stop is not engaged"}})
def release(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop

    def _release() -> None:
        loop.chain["hes"].release()  # InvalidState (-> 409) when not engaged
        loop.clear_fault()

    runtime.call(_release)
    return Ok(message="hard e-stop released")


motion_router = APIRouter(prefix="/api/motion", tags=["emergency"])


@motion_router.post("/stop", response_model=Ok,
                    summary="Stop and revert the planned motion ([MLC] Eq. 15); balance keeps working")
def stop_motion(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    runtime.call(lambda: loop.chain["es"].stop_motion())
    return Ok(message="planned motion stopped")


@motion_router.post("/release", response_model=Ok,
                    summary="Release the motion stop: blend back to the live plan over recover_time_s",
                    responses={409: {"description": "the motion is not stopped"}})
def release_motion(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    runtime.call(lambda: loop.chain["es"].release_motion())
    return Ok(message="motion stop released")


# ---- EmergencyStopper parameters: one view over the layers that own them ---------------------------------

#: presented name -> (owning chain layer, field of that layer's Params dataclass). The revert timing lives in
#: the EmergencyStopper's params, the capture-point flag that triggers it in the Stabilizer's.
ES_PARAMS: dict[str, tuple[str, str]] = {
    "t1": ("es", "t1_s"),
    "t2": ("es", "t2_s"),
    "recover_time": ("es", "recover_time_s"),
    "threshold": ("st", "cp_threshold_m"),
    "mode": ("st", "emergency_mode"),
}

_ES_PARAM_ERRORS = {422: {"description": "unknown parameter (valid names listed), wrong type or out of range "
                                         "(the message names the field and its range)"},
                    404: {"description": "a layer owning these parameters is not in the chain"}}

EsChangesBody = Annotated[dict[str, Any], Body(
    description="{parameter name: new value} for some of " + ", ".join(ES_PARAMS) + ", e.g. {\"t1\": 0.8}")]


class _View:
    """The presented parameters as `check_types` reads a Params object."""

    def __init__(self, values: dict[str, Any]) -> None:
        self._values = values

    def to_dict(self) -> dict[str, Any]:
        return dict(self._values)


def _owners(chain, table: dict[str, tuple[str, str]]) -> dict[str, Any]:
    """{layer name: its current Params} of the layers the table names."""
    out = {}
    for layer, _ in table.values():
        if layer not in chain:
            raise HTTPException(status_code=404, detail=f"no layer {layer!r} in the chain; present: {chain.order()}")
        out[layer] = chain[layer].params
    return out


def _field_meta(params, name: str) -> dict[str, Any]:
    return dict(next(f.metadata for f in dataclasses.fields(params) if f.name == name))


def composite_view(chain, table: dict[str, tuple[str, str]]) -> dict[str, Any]:
    """{"params": {name: value}, "schema": [{name, default, unit, min, max, choices, layer, param}...]}, each
    entry taken from the owning layer's Params declaration."""
    owners = _owners(chain, table)
    values, schema = {}, []
    for name, (layer, param) in table.items():
        p = owners[layer]
        values[name] = getattr(p, param)
        declared = next(d for d in type(p).describe() if d["name"] == param)
        schema.append({**declared, "name": name, "layer": layer, "param": f"{type(p).__name__}.{param}"})
    return jsonable({"params": values, "schema": schema})


def _range_text(meta: dict[str, Any]) -> str:
    unit = meta.get("unit", "")
    lo, hi = meta.get("min"), meta.get("max")
    return f"[{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}] {unit}".rstrip()


def composite_changes(owners: dict[str, Any], table: dict[str, tuple[str, str]], changes: dict[str, Any],
                      prefix: str = "") -> dict[str, dict[str, Any]]:
    """{layer: {param: value}} from {presented name: value}: names, types, ranges and choices checked
    against the owning Params (`owners`: {layer: Params}), each rejection naming the presented field,
    after `prefix` (-> 422)."""
    unknown = sorted(set(changes) - set(table))
    if unknown:
        raise BadRequest(prefix + unknown[0], f"unknown parameter(s) {unknown}; valid: {list(table)}")
    current = {name: getattr(owners[layer], param) for name, (layer, param) in table.items()}
    try:
        typed = check_types(_View(current), changes)
    except BadRequest as exc:
        raise BadRequest(prefix + exc.field, exc.message) from None
    grouped: dict[str, dict[str, Any]] = {}
    for name, value in typed.items():
        layer, param = table[name]
        try:
            owners[layer].replaced(**{param: value})
        except InvalidCommand as exc:
            meta = _field_meta(owners[layer], param)
            owner = f"{type(owners[layer]).__name__}.{param}"
            if meta.get("choices") is not None:
                msg = f"{value!r} is not one of the allowed {list(meta['choices'])} ({owner})"
            elif isinstance(value, (int, float)):
                msg = f"{value:g} {meta.get('unit', '')} is outside the allowed range {_range_text(meta)} ({owner})"
            else:
                msg = f"{exc}"
            raise BadRequest(prefix + name, msg) from exc
        grouped.setdefault(layer, {})[param] = value
    return grouped


def _apply_grouped(loop, grouped: dict[str, dict[str, Any]]) -> None:
    """Inside the loop: every owning layer's params replaced whole, all or none."""
    chain = loop.chain  # the chain of this tick (a reset rebuilds it)
    new = {layer: chain[layer].params.replaced(**fields) for layer, fields in grouped.items()}
    for layer, params in new.items():
        chain[layer].set_params(params)


params_router = APIRouter(prefix="/api/emergency-stopper", tags=["emergency"])


@params_router.get("/params", responses=_ES_PARAM_ERRORS,
                   summary="EmergencyStopper parameters: T1, T2, recover time [s] and the Stabilizer's "
                           "capture-point flag (threshold [m], mode), with units, defaults and ranges")
def get_es_params(runtime: RuntimeDep) -> dict[str, Any]:
    return composite_view(runtime.loop.chain, ES_PARAMS)


@params_router.put("/params", responses=_ES_PARAM_ERRORS,
                   summary="Change some EmergencyStopper parameters (validated; each owning layer's params "
                           "replaced whole at a tick boundary)")
def put_es_params(runtime: RuntimeDep, changes: EsChangesBody) -> dict[str, Any]:
    loop = runtime.loop
    grouped = composite_changes(_owners(loop.chain, ES_PARAMS), ES_PARAMS, changes)

    def _apply():
        _apply_grouped(loop, grouped)
        return composite_view(loop.chain, ES_PARAMS)

    return runtime.call(_apply)
