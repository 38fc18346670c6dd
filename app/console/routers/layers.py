"""Layer parameters and start/stop of the AutoBalancer and the Stabilizer, derived from each layer's Params
dataclass: the controller declares (names, defaults, units, ranges, choices), the app only renders."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.params_http import ChangesBody, params_changes_body, params_document
from app.console.schemas import Ok

#: URL segment -> chain layer name (hrpsys component), with the label used in summaries.
LAYERS: dict[str, tuple[str, str]] = {
    "auto-balancer": ("abc", "AutoBalancer"),
    "stabilizer": ("st", "Stabilizer"),
}

def _add_routes(router: APIRouter, segment: str, layer: str, label: str) -> None:
    from controller.system import layer_params_classes

    base = f"/{segment}"
    body = params_changes_body(layer_params_classes()[layer])

    def get_params(service: ServiceDep) -> dict[str, Any]:
        return params_document(service.params(layer)[layer])

    def put_params(service: ServiceDep, changes: ChangesBody) -> dict[str, Any]:
        return params_document(service.set_params({layer: changes})[layer])

    def start(service: ServiceDep) -> Ok:
        return Ok(message=service.start_layer(layer))

    def stop(service: ServiceDep) -> Ok:
        return Ok(message=service.stop_layer(layer))

    router.add_api_route(f"{base}/params", get_params, methods=["GET"], name=f"{segment}-get-params",
                         summary=f"{label} parameters and their schema (unit, default, range, choices)",
                         responses=errors(404))
    router.add_api_route(f"{base}/params", put_params, methods=["PUT"], name=f"{segment}-put-params",
                         summary=f"Change some {label} parameters (validated, applied at a tick boundary)",
                         responses=errors(404, 422), openapi_extra=body)
    router.add_api_route(f"{base}/start", start, methods=["POST"], response_model=Ok, name=f"{segment}-start",
                         summary=f"Start the {label} (blends in)", responses=errors(409))
    router.add_api_route(f"{base}/stop", stop, methods=["POST"], response_model=Ok, name=f"{segment}-stop",
                         summary=f"Stop the {label} (blends out)", responses=errors(409))


router = APIRouter(prefix="/api", tags=["layers"])
for _segment, (_name, _label) in LAYERS.items():
    _add_routes(router, _segment, _name, _label)
