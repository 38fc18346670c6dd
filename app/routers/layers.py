"""Layer parameters and start/stop, derived from each layer's Params dataclass: the controller declares
(names, defaults, units, ranges, choices), the app only renders. No per-field code here."""

from __future__ import annotations

import math
from typing import Annotated, Any

from fastapi import APIRouter, Body, HTTPException

from app.deps import RuntimeDep
from app.errors import BadRequest
from app.runtime import Runtime, jsonable
from app.schemas import Ok

#: URL segment -> chain layer name (hrpsys component), with the label used in messages.
LAYERS: dict[str, tuple[str, str]] = {
    "auto-balancer": ("abc", "AutoBalancer"),
    "stabilizer": ("st", "Stabilizer"),
}

_PARAM_ERRORS = {422: {"description": "unknown parameter (valid names listed), wrong type or out of range "
                                      "(the message names the field and its range)"},
                 404: {"description": "the layer is not in the chain"}}
_STATE_ERRORS = {409: {"description": "already running / not running"},
                 404: {"description": "the layer is not in the chain"}}


ChangesBody = Annotated[dict[str, Any], Body(
    description="{parameter name: new value}, e.g. {\"cp_threshold_m\": 0.05}")]


def _layer(runtime: Runtime, name: str):
    chain = runtime.loop.chain
    if name not in chain:
        raise HTTPException(status_code=404, detail=f"no layer {name!r} in the chain; present: {chain.order()}")
    return chain[name]


def params_view(params) -> dict[str, Any]:
    """{"params": current values, "schema": [{name, default, unit, min, max, choices}...]}."""
    return jsonable({"params": params.to_dict(), "schema": type(params).describe()})


def check_types(params, changes: dict[str, Any]) -> dict[str, Any]:
    """Coerce JSON values to the type of each field's current value (int -> float for float fields);
    reject wrong types and non-finite numbers naming the field. Unknown names are left to
    `Params.replaced`, which lists the valid ones."""
    if not changes:
        raise BadRequest("body", f"give at least one parameter; valid: {sorted(params.to_dict())}")
    current = params.to_dict()
    out: dict[str, Any] = {}
    for key, value in changes.items():
        if key not in current:
            out[key] = value
            continue
        kind = type(current[key])
        if kind is bool:
            if not isinstance(value, bool):
                raise BadRequest(key, f"must be true or false (got {value!r})")
        elif kind in (int, float):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise BadRequest(key, f"must be a number (got {value!r})")
            if not math.isfinite(value):
                raise BadRequest(key, f"must be a finite number (got {value!r})")
            if kind is int and not float(value).is_integer():
                raise BadRequest(key, f"must be an integer (got {value!r})")
            value = kind(value)
        elif kind is str and not isinstance(value, str):
            raise BadRequest(key, f"must be a string (got {value!r})")
        out[key] = value
    return out


def _add_routes(router: APIRouter, segment: str, layer_name: str, label: str) -> None:
    base = f"/{segment}"

    def get_params(runtime: RuntimeDep) -> dict[str, Any]:
        return params_view(_layer(runtime, layer_name).params)

    def put_params(runtime: RuntimeDep, changes: ChangesBody) -> dict[str, Any]:
        layer = _layer(runtime, layer_name)
        typed = check_types(layer.params, changes)
        loop = runtime.loop

        def _apply():
            target = loop.chain[layer_name]  # the chain of this tick (a reset rebuilds it)
            new = target.params.replaced(**typed)  # InvalidCommand (-> 422) names field and range
            target.set_params(new)
            return new

        return params_view(runtime.call(_apply))

    def start(runtime: RuntimeDep) -> Ok:
        _layer(runtime, layer_name)
        loop = runtime.loop
        runtime.call(lambda: loop.chain[layer_name].start())  # InvalidState -> 409
        return Ok(message=f"{label} started")

    def stop(runtime: RuntimeDep) -> Ok:
        _layer(runtime, layer_name)
        loop = runtime.loop
        runtime.call(lambda: loop.chain[layer_name].stop())  # InvalidState -> 409
        return Ok(message=f"{label} stopped")

    router.add_api_route(f"{base}/params", get_params, methods=["GET"], name=f"{segment}-get-params",
                         summary=f"{label} parameters and their schema (unit, default, range, choices)",
                         responses=_PARAM_ERRORS)
    router.add_api_route(f"{base}/params", put_params, methods=["PUT"], name=f"{segment}-put-params",
                         summary=f"Change some {label} parameters (validated, applied at a tick boundary)",
                         responses=_PARAM_ERRORS)
    router.add_api_route(f"{base}/start", start, methods=["POST"], response_model=Ok, name=f"{segment}-start",
                         summary=f"Start the {label} (blends in)", responses=_STATE_ERRORS)
    router.add_api_route(f"{base}/stop", stop, methods=["POST"], response_model=Ok, name=f"{segment}-stop",
                         summary=f"Stop the {label} (blends out)", responses=_STATE_ERRORS)


router = APIRouter(prefix="/api", tags=["layers"])
for _segment, (_name, _label) in LAYERS.items():
    _add_routes(router, _segment, _name, _label)
