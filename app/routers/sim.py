"""Simulation controls: reset (optionally to another scene), push a body, list scenes."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Body

from app.deps import RuntimeDep
from app.schemas import Ok, PushRequest, ResetRequest
from app.validation import body_name, push_force, scene_name

router = APIRouter(prefix="/api/sim", tags=["simulation"])


@router.get("/scenes", summary="Scenes the simulation can be reset to")
def scenes(runtime: RuntimeDep) -> dict[str, list[str] | str]:
    return {"scenes": runtime.available_scenes(), "current": runtime.scene}


@router.post("/reset", response_model=Ok, summary="Restart the simulation (and the controller chain)")
def reset(runtime: RuntimeDep, req: Annotated[ResetRequest | None, Body()] = None) -> Ok:
    scene = None
    if req is not None and req.scene is not None:
        scene = scene_name(runtime, req.scene)
    runtime.reset(scene)
    return Ok(message=f"simulation reset (scene {runtime.scene!r})")


@router.post("/push", response_model=Ok, summary="Apply a world-frame force at a body's COM for a while")
def push(req: PushRequest, runtime: RuntimeDep) -> Ok:
    body = body_name(runtime, req.body)
    force = push_force(req.force)
    duration = float(req.duration)
    loop = runtime.loop
    runtime.call(lambda: loop.plant.push(body, force, duration))
    return Ok(message=f"pushing {body} for {duration:g} s")
