"""FastAPI dependencies: the runtime and the settings, overridable in tests."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, HTTPException, Request

from app.runtime import Runtime
from app.settings import Settings


def get_runtime(request: Request) -> Runtime:
    runtime = getattr(request.app.state, "runtime", None)
    if runtime is None:
        raise HTTPException(status_code=503, detail="the simulation runtime is not running")
    return runtime


def get_settings(request: Request) -> Settings:
    return getattr(request.app.state, "settings", None) or Settings()


RuntimeDep = Annotated[Runtime, Depends(get_runtime)]
SettingsDep = Annotated[Settings, Depends(get_settings)]
