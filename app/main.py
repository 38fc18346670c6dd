"""The FastAPI application: assembles the routers, the error handlers and the static operator page."""

from __future__ import annotations

from contextlib import asynccontextmanager
from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import FileResponse
from fastapi.staticfiles import StaticFiles

from app.errors import install_error_handlers
from app.routers import chain, emergency, experiments, impedance, layers, sequence, sim, state, walk
from app.runtime import Runtime
from app.settings import Settings

STATIC_DIR = Path(__file__).resolve().parents[1] / "static"


def create_app(settings: Settings | None = None, runtime: Runtime | None = None) -> FastAPI:
    """The console app. With `runtime`, serve it (its owner starts and stops it); with only `settings`,
    build and run a Runtime for the app's lifetime; with neither, routes need a dependency override."""

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        app.state.settings = settings or Settings()
        owned = None
        if runtime is not None:
            app.state.runtime = runtime
        elif settings is not None:
            owned = Runtime(scene=settings.scene, dt_control_s=settings.dt_control_s, speed=settings.speed)
            owned.start()
            app.state.runtime = owned
        try:
            yield
        finally:
            if owned is not None:
                owned.stop()
            app.state.runtime = None

    app = FastAPI(title="HRP-2 operator console", version="0.1.0", lifespan=lifespan,
                  description="Operator API of the simulated HRP-2 No.10: state, e-stop, motion stop, "
                              "sequence player, walking, layer parameters, impedance, experiments, "
                              "simulation controls. Units: m, s, deg, N.")
    app.state.settings = settings or Settings()
    app.state.runtime = runtime
    install_error_handlers(app)
    for module in (state, emergency, sequence, sim, chain, layers, walk, impedance, experiments):
        app.include_router(module.router)
    app.include_router(emergency.motion_router)
    app.include_router(emergency.params_router)

    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(STATIC_DIR / "index.html")

    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")
    return app


#: For `uvicorn app.main:app`: default settings, without the viser viewer.
app = create_app(Settings(viewer_port=None))
