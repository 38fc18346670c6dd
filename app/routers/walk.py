"""Walking commands (hrpsys AutoBalancerService in REST form): goPos, goVelocity, goStop, emergency
walking stop, setFootSteps, and the remaining footsteps. Checked here, applied at a tick boundary."""

from __future__ import annotations

import math

import numpy as np
from fastapi import APIRouter, HTTPException

from app.deps import RuntimeDep
from app.runtime import Runtime, jsonable
from app.schemas import FootstepsRequest, GoPosRequest, GoVelocityRequest, Ok, WalkFootsteps
from app.validation import step_params

router = APIRouter(prefix="/api/walk", tags=["walk"])

_ERRORS = {422: {"description": "invalid field: the message names it and what is allowed"},
           409: {"description": "the AutoBalancer is not running (or already walking a footstep list)"},
           404: {"description": "no AutoBalancer in the chain"}}


def _abc(runtime: Runtime):
    """The AutoBalancer of the chain of this tick (a reset rebuilds the chain); call inside the loop."""
    chain = runtime.loop.chain
    if "abc" not in chain:
        raise HTTPException(status_code=404, detail=f"no AutoBalancer ('abc') in the chain; present: {chain.order()}")
    return chain["abc"]


@router.post("/go-pos", response_model=Ok, responses=_ERRORS,
             summary="Walk to (x, y, theta) relative to the current feet (goPos)")
def go_pos(req: GoPosRequest, runtime: RuntimeDep) -> Ok:
    x, y, theta_rad = float(req.x), float(req.y), math.radians(req.theta_deg)
    _abc(runtime)
    n = runtime.call(lambda: _abc(runtime).go_pos(x, y, theta_rad))
    return Ok(message=f"walking to ({x:g} m, {y:g} m, {req.theta_deg:g} deg) in {n} footsteps")


@router.post("/go-velocity", response_model=Ok, responses=_ERRORS,
             summary="Walk at a velocity until stopped (goVelocity); clamped to the stride limits")
def go_velocity(req: GoVelocityRequest, runtime: RuntimeDep) -> Ok:
    vx, vy, vtheta_rad_s = float(req.vx), float(req.vy), math.radians(req.vtheta_deg)
    _abc(runtime)
    runtime.call(lambda: _abc(runtime).go_velocity(vx, vy, vtheta_rad_s))
    return Ok(message=f"walking at ({vx:g} m/s, {vy:g} m/s, {req.vtheta_deg:g} deg/s)")


@router.post("/stop", response_model=Ok, responses=_ERRORS,
             summary="Stop walking after the committed steps, feet side by side (goStop)")
def stop(runtime: RuntimeDep) -> Ok:
    _abc(runtime)
    runtime.call(lambda: _abc(runtime).go_stop())
    return Ok(message="stopping")


@router.post("/emergency-stop", response_model=Ok, responses=_ERRORS,
             summary="Stop walking in place as soon as possible (emergencyStop); the arms are left alone")
def emergency_stop(runtime: RuntimeDep) -> Ok:
    _abc(runtime)
    runtime.call(lambda: _abc(runtime).emergency_stop_walking())
    return Ok(message="walking emergency stop")


@router.post("/footsteps", response_model=Ok, responses=_ERRORS,
             summary="Walk a footstep list (setFootSteps), relative to the first, which is the support foot")
def set_footsteps(req: FootstepsRequest, runtime: RuntimeDep) -> Ok:
    steps = [(f.leg, [float(v) for v in f.pos], [math.radians(v) for v in f.rpy_deg]) for f in req.footsteps]
    sp = step_params(req.step)
    per_step = None if sp is None else [None] + [sp] * (len(steps) - 1)
    _abc(runtime)
    n = runtime.call(lambda: _abc(runtime).set_footsteps(steps, per_step))
    return Ok(message=f"walking {n} footsteps")


@router.get("/footsteps", response_model=WalkFootsteps,
            summary="Whether walking, and the footsteps not yet landed (pos [m], rpy [rad] and rpy_deg [deg])",
            responses={404: _ERRORS[404]})
def remaining_footsteps(runtime: RuntimeDep) -> WalkFootsteps:
    _abc(runtime)

    def _read():
        abc = _abc(runtime)
        return bool(abc.gait.walking), abc.remaining_footsteps()

    walking, footsteps = runtime.call(_read)
    for f in footsteps:
        f["rpy_deg"] = [round(float(v), 4) for v in np.rad2deg(f["rpy"])]
    return WalkFootsteps(walking=walking, footsteps=jsonable(footsteps))
