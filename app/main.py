"""The FastAPI application: assembles the routers, the error handlers, the front-door guard and the static
operator page. Serves an OperatorService its owner built (the CLI: the robot in its own process)."""

from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import FileResponse, HTMLResponse
from fastapi.staticfiles import StaticFiles

from app.errors import ErrorBody, install_error_handlers
from app.hot_paths import HotPaths
from app.routers import (
    behaviors,
    chain,
    emergency,
    experiments,
    impedance,
    layers,
    operator,
    params,
    sequence,
    sim,
    state,
    walk,
)
from app.security import ConsoleGuard, allowed_hosts_for
from app.service import OperatorService
from app.settings import Settings

STATIC_DIR = Path(__file__).resolve().parents[1] / "static"


def create_app(settings: Settings | None = None, service: OperatorService | None = None):
    """The console's ASGI app: FastAPI behind the guard. Its FastAPI instance is `.fastapi`."""
    settings = settings or Settings()
    api = FastAPI(title="HRP-2 operator console", version="0.1.0",
                  description="Operator API of the simulated HRP-2 No.10: state, e-stop, motion stop, "
                              "sequence player, walking, layer parameters, impedance, experiments, "
                              "simulation controls, the operator's velocities at the operational points "
                              "(feet frame) and the behaviours. Units: m, s, deg, N. Control requests (POST, PUT) "
                              "must be sent as JSON (Content-Type: application/json); only POST /api/estop is "
                              "accepted without. Bodies are limited to 64 kB.")
    api.state.settings = settings
    api.state.service = service
    install_error_handlers(api)
    from starlette.exceptions import HTTPException as StarletteHTTPException

    api.add_exception_handler(StarletteHTTPException, behaviors.unknown_behavior_handler)
    for module in (state, emergency, sequence, sim, chain, layers, params, walk, impedance, experiments, operator,
                   behaviors):
        api.include_router(module.router)
    api.include_router(operator.ws_router)
    api.include_router(emergency.motion_router)
    api.include_router(emergency.params_router)
    _publish_error_schema(api)

    @api.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(STATIC_DIR / "index.html")

    @api.get("/viewer/", include_in_schema=False)
    def viewer_client() -> HTMLResponse:
        # viser's client with the page's key forwarder (the 3D view's iframe; its websocket goes to the viewer port)
        from app.viewer_client import client_html

        return HTMLResponse(client_html())

    api.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    guarded = ConsoleGuard(HotPaths(api), allowed_hosts_for(settings.host, settings.extra_hosts))
    guarded.fastapi = api
    return guarded


def _publish_error_schema(api: FastAPI) -> None:
    """OpenAPI's 422 responses say what the handlers send ({"detail": str, ...}), not FastAPI's default."""
    original = api.openapi

    def openapi():
        if api.openapi_schema is not None:
            return api.openapi_schema
        schema = original()
        components = schema.setdefault("components", {}).setdefault("schemas", {})
        error_schema = ErrorBody.model_json_schema(ref_template="#/components/schemas/{model}")
        for name, sub in error_schema.pop("$defs", {}).items():
            components[name] = sub
        components["ErrorBody"] = error_schema
        components["HTTPValidationError"] = error_schema
        components.pop("ValidationError", None)
        for path in schema.get("paths", {}).values():
            for op in path.values():
                resp = op.get("responses", {}).get("422")
                if resp is not None:
                    resp["content"] = {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorBody"}}}
        return schema

    api.openapi = openapi
