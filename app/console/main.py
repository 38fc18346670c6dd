"""The FastAPI application: assembles the routers, the error handlers, the front-door guard and the static
operator page. Serves an OperatorService its owner built (the CLI: the robot in its own process)."""

from __future__ import annotations

import mimetypes
from pathlib import Path

from fastapi import FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse
from fastapi.staticfiles import StaticFiles

from app.console.command_journal import CommandJournal, JournalingLayer
from app.console.errors import COMMON_ERRORS, CONTROL_ERRORS, ErrorBody, install_error_handlers
from app.console.hot_paths import HotPaths
from app.console.operator_lock import OperatorLock
from app.console.routers import (
    behaviors,
    camera,
    chain,
    emergency,
    experiments,
    impedance,
    layers,
    operator,
    params,
    places,
    sequence,
    sessions,
    sim,
    state,
    telemetry,
    walk,
)
from app.console.security import LOCK_EXEMPT, UNSAFE_METHODS, ConsoleGuard, allowed_hosts_for, check_token_config
from app.console.settings import Settings
from app.service import OperatorService

STATIC_DIR = Path(__file__).resolve().parents[2] / "static"
# the page's scripts are ES modules, which a browser runs only if served as JavaScript (a system's MIME table may
# say otherwise for .js)
mimetypes.add_type("text/javascript", ".js")


def create_app(settings: Settings | None = None, service: OperatorService | None = None):
    """The console's ASGI app: FastAPI behind the guard. Its FastAPI instance is `.fastapi`. Raises
    app.console.security.TokenRequired for a host beyond loopback without a token."""
    settings = settings or Settings()
    check_token_config(settings.host, settings.token)
    api = FastAPI(title="HRP-2 operator console", version="0.1.0", docs_url=None, redoc_url=None,
                  description="Operator API of the simulated HRP-2 No.10: state, e-stop, motion stop, "
                              "sequence player, walking, layer parameters, impedance, experiments, "
                              "simulation controls, the operator's velocities at the operational points "
                              "(feet frame) and the behaviours. Units: m, s, deg, N. Control requests (POST, PUT) "
                              "must be sent as JSON (Content-Type: application/json); only POST /api/estop is "
                              "accepted without. Bodies are limited to 64 kB. A console bound beyond loopback needs "
                              "its token on every /api/ request (Authorization: Bearer <token>) and every WebSocket "
                              "(?token=<token>). While a client holds the operator lock (POST /api/operator/lock), "
                              "control requests without its lease token (header X-Lock-Token; WebSockets "
                              "?lock_token=) are answered 423 naming the holder; the e-stop never is.")
    api.state.settings = settings
    api.state.service = service
    lock = api.state.lock = OperatorLock(settings.lock_lease_s, settings.lock_grace_s)
    journal = api.state.journal = CommandJournal()
    install_error_handlers(api)
    from starlette.exceptions import HTTPException as StarletteHTTPException

    api.add_exception_handler(StarletteHTTPException, behaviors.unknown_behavior_handler)
    for module in (state, emergency, sequence, sim, chain, layers, params, walk, impedance, experiments, operator,
                   behaviors, sessions, places):
        api.include_router(module.router)
    api.include_router(operator.ws_router)
    api.include_router(telemetry.router)
    api.include_router(camera.router)
    api.include_router(emergency.motion_router)
    api.include_router(emergency.params_router)
    if settings.test_hooks:
        api.include_router(sim.hooks_router)
    _publish_error_schema(api)

    @api.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(STATIC_DIR / "index.html")

    @api.get("/viewer/", include_in_schema=False)
    def viewer_client() -> HTMLResponse:
        # viser's client with the page's key forwarder (the 3D view's iframe; its websocket goes to the viewer port)
        from app.console.viewer_client import client_html

        return HTMLResponse(client_html())

    _serve_docs(api)
    api.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    # the front door, then the journal of what passed it (app.console.command_journal), then the hot paths
    guarded = ConsoleGuard(JournalingLayer(HotPaths(api), journal),
                           allowed_hosts_for(settings.host, settings.extra_hosts), token=settings.token, lock=lock)
    guarded.fastapi = api
    return guarded


def _serve_docs(api: FastAPI) -> None:
    """/docs with Swagger UI's own files from the swagger-ui-bundle-v2 package: nothing from the internet."""
    from swagger_ui_bundle import swagger_ui_path

    api.mount("/static/swagger-ui", StaticFiles(directory=str(swagger_ui_path)), name="swagger-ui")

    @api.get("/docs", include_in_schema=False)
    def docs() -> HTMLResponse:
        return get_swagger_ui_html(openapi_url="/openapi.json", title=f"{api.title} - API",
                                   swagger_js_url="/static/swagger-ui/swagger-ui-bundle.js",
                                   swagger_css_url="/static/swagger-ui/swagger-ui.css",
                                   swagger_favicon_url="/static/swagger-ui/favicon-32x32.png")


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
        for template, path in schema.get("paths", {}).items():
            for method, op in path.items():
                responses = op.setdefault("responses", {})
                # the front door's answers: the token on every /api/ path, the lock on control requests
                extra = {401: COMMON_ERRORS[401]}
                if method.upper() in UNSAFE_METHODS and (method.upper(), template) not in LOCK_EXEMPT:
                    extra.update(CONTROL_ERRORS)
                for code, spec in extra.items():
                    responses.setdefault(str(code), {
                        "description": spec["description"],
                        "content": {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorBody"}}}})
                resp = responses.get("422")
                if resp is not None:
                    resp["content"] = {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorBody"}}}
        return schema

    api.openapi = openapi
