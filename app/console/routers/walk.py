"""Walking commands (hrpsys AutoBalancerService in REST form): goPos, goVelocity, goStop, emergency
walking stop, setFootSteps, and the remaining footsteps."""

from __future__ import annotations

import math

from fastapi import APIRouter

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.schemas import FootstepsRequest, GoPosRequest, GoVelocityRequest, Ok, WalkFootsteps
from app.console.state import jsonable
from app.service.verbs import Footstep, step_params

router = APIRouter(prefix="/api/walk", tags=["walk"])

_WALK_ERRORS = errors(404, 409, 422, e409="refused: the e-stop, a fall, the AutoBalancer not running, or "
                                          "already walking a footstep list (`reason` says which)")
_GO_POS_ERRORS = errors(404, 409, 422, e409="refused: the e-stop, a fall, the AutoBalancer not running, the "
                                            "emergency walking stop in force, or the stop after an e-stop still "
                                            "playing (`reason` says which)")


@router.post("/go-pos", response_model=Ok, responses=_GO_POS_ERRORS,
             summary="Walk to (x, y, theta) relative to the current feet (goPos); while walking, as hrpsys, "
                     "relative to the feet where the walk began, replacing the rest of the plan from the next "
                     "free footstep")
def go_pos(req: GoPosRequest, service: ServiceDep) -> Ok:
    return Ok(message=service.go_pos(req.x, req.y, math.radians(req.theta_deg)))


@router.post("/go-velocity", response_model=Ok, responses=_WALK_ERRORS,
             summary="Walk at a velocity until stopped (goVelocity); clamped to the stride limits")
def go_velocity(req: GoVelocityRequest, service: ServiceDep) -> Ok:
    return Ok(message=service.go_velocity(req.vx, req.vy, math.radians(req.vtheta_deg)))


@router.post("/stop", response_model=Ok, responses=errors(404),
             summary="Stop walking after the committed steps, feet side by side (goStop)")
def stop(service: ServiceDep) -> Ok:
    return Ok(message=service.walk_stop())


@router.post("/emergency-stop", response_model=Ok, responses=errors(404, 409, e409="not walking: nothing to stop"),
             summary="Stop walking in place as soon as possible (emergencyStop); the arms are left alone")
def emergency_stop(service: ServiceDep) -> Ok:
    return Ok(message=service.walk_emergency_stop())


@router.post("/footsteps", response_model=Ok, responses=_WALK_ERRORS,
             summary="Walk a footstep list (setFootSteps), relative to the first, which is the support foot")
def set_footsteps(req: FootstepsRequest, service: ServiceDep) -> Ok:
    steps = [Footstep(f.leg, tuple(f.pos), tuple(math.radians(v) for v in f.rpy_deg)) for f in req.footsteps]
    sp = None
    if req.step is not None:
        dt = service.info.dt_control_s
        step_time = None if req.step.step_time is None else max(1, round(req.step.step_time / dt)) * dt
        given = {"step_height_m": req.step.step_height, "step_time_s": step_time,
                 "toe_angle_rad": None if req.step.toe_angle_deg is None else math.radians(req.step.toe_angle_deg),
                 "heel_angle_rad": None if req.step.heel_angle_deg is None else math.radians(req.step.heel_angle_deg)}
        sp = step_params({k: v for k, v in given.items() if v is not None})
    return Ok(message=service.set_footsteps(steps, sp))


@router.get("/footsteps", response_model=WalkFootsteps, responses=errors(404),
            summary="Whether walking, and the footsteps not yet landed (pos [m], rpy [rad] and rpy_deg [deg])")
def remaining_footsteps(service: ServiceDep) -> WalkFootsteps:
    walking, footsteps = service.footsteps()
    out = []
    for f in jsonable(footsteps):
        f["rpy_deg"] = [round(math.degrees(v), 4) for v in f["rpy"]]
        out.append(f)
    return WalkFootsteps(walking=walking, footsteps=out)
