"""SequencePlayer commands (hrpsys SequencePlayerService in REST form): joint angles, target pose, clear."""

from __future__ import annotations

import math

from fastapi import APIRouter

from app.deps import ServiceDep
from app.errors import errors
from app.schemas import JointAnglesRequest, Ok, SequenceStatus, TargetPoseRequest

router = APIRouter(prefix="/api/sequence", tags=["sequence"])


@router.post("/joint-angles", response_model=Ok, responses=errors(409, 422),
             summary="Interpolate to joint angles (all 30 as a list, or some by name) in `time` s")
def joint_angles(req: JointAnglesRequest, service: ServiceDep) -> Ok:
    if isinstance(req.angles_deg, dict):
        return Ok(message=service.set_some_joint_angles(
            {name: math.radians(v) for name, v in req.angles_deg.items()}, req.time))
    return Ok(message=service.set_joint_angles([math.radians(v) for v in req.angles_deg], req.time))


@router.post("/target-pose", response_model=Ok, responses=errors(409, 422),
             summary="Move a limb's end effector to a pose (relative to `frame` if given) in `time` s")
def target_pose(req: TargetPoseRequest, service: ServiceDep) -> Ok:
    return Ok(message=service.set_target_pose(req.limb, req.pos, [math.radians(v) for v in req.rpy_deg], req.time,
                                              req.frame))


@router.post("/clear", response_model=Ok, responses=errors(), summary="Stop the interpolation where it is")
def clear(service: ServiceDep) -> Ok:
    return Ok(message=service.clear_sequence())


@router.get("/status", response_model=SequenceStatus, responses=errors(),
            summary="Whether a motion is being interpolated")
def status(service: ServiceDep) -> SequenceStatus:
    return SequenceStatus(interpolating=service.is_interpolating())
