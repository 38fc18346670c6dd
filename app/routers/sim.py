"""Simulation controls: reset (optionally to another scene; a new robot process if the old one died),
push a body, list scenes."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Body

from app.deps import ServiceDep
from app.errors import errors
from app.schemas import Ok, PushRequest, ResetRequest

router = APIRouter(prefix="/api/sim", tags=["simulation"])


@router.get("/scenes", summary="Scenes the simulation can be reset to")
def scenes(service: ServiceDep) -> dict[str, list[str] | str]:
    return {"scenes": list(service.info.scenes), "current": service.info.scene}


@router.post("/reset", response_model=Ok, responses=errors(422),
             summary="Restart the simulation and the controller chain (a new robot process if it had died)")
def reset(service: ServiceDep, req: Annotated[ResetRequest | None, Body()] = None) -> Ok:
    return Ok(message=service.reset(None if req is None else req.scene))


@router.post("/push", response_model=Ok, responses=errors(404, 422, e404="no such body (the valid ones are listed)"),
             summary="Apply a world-frame force at a body's COM for a while")
def push(req: PushRequest, service: ServiceDep) -> Ok:
    return Ok(message=service.push(req.body, req.force, req.duration))
