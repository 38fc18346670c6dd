"""Simulation controls: reset (optionally to another scene; a new robot process if the old one died),
push a body, place a scene object, list scenes and objects."""

from __future__ import annotations

import math
from typing import Annotated

from fastapi import APIRouter, Body, Path

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.schemas import FaultRequest, ObjectPlaced, Ok, PlaceObjectRequest, PushRequest, ResetRequest

router = APIRouter(prefix="/api/sim", tags=["simulation"])
#: only on a console started with HRP2_TEST_HOOKS=1 (Settings.test_hooks): the browser tests' way to a fault
hooks_router = APIRouter(prefix="/api/sim", tags=["simulation"])


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


@router.get("/objects", summary="The current scene's objects a simulator operation may place")
def objects(service: ServiceDep) -> dict[str, list[str] | str]:
    return {"objects": list(service.objects), "scene": service.info.scene}


@router.put("/objects/{name}", response_model=ObjectPlaced,
            responses=errors(404, 422, e404="no such object in this scene (the valid ones are listed)"),
            summary="Place a scene object (position, yaw) at rest: a simulator operation the robot only sees")
def place_object(name: Annotated[str, Path(max_length=64)], req: PlaceObjectRequest,
                 service: ServiceDep) -> ObjectPlaced:
    placed = service.place_object(name, req.position, math.radians(req.yaw_deg))
    where = ", ".join(f"{v:.3f}" for v in placed)
    return ObjectPlaced(message=f"{name} placed at ({where}) m, yaw {req.yaw_deg:g} deg", name=name,
                        position=list(placed))


@hooks_router.post("/fault", response_model=Ok, responses=errors(404, 422, e404="no such layer (the valid ones "
                                                                              "are listed)"),
                   summary="Test hook (HRP2_TEST_HOOKS=1 only): make a layer raise, or put a NaN in the physics; "
                           "the hard stop engages with the fault, POST /api/sim/reset recovers")
def inject_fault(req: FaultRequest, service: ServiceDep) -> Ok:
    return Ok(message=service.inject_fault(req.kind, req.layer))
