"""SequencePlayer commands (hrpsys SequencePlayerService in REST form): joint angles, target pose, clear."""

from __future__ import annotations

import math

from fastapi import APIRouter

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.schemas import JointAnglesRequest, Ok, SequenceStatus, TargetPoseRequest

router = APIRouter(prefix="/api/sequence", tags=["sequence"])


def _joint_angles_body() -> dict:
    """The body of /joint-angles with each joint's own range (from the model) rather than the +-360 deg the
    request model checks first (the robot's limits are checked once, by the verb)."""
    from robot.generate import joint_limits_deg

    limits = joint_limits_deg()
    per_joint = {n: {"type": "number", "minimum": lo, "maximum": hi, "description": f"{n} [deg]"}
                 for n, (lo, hi) in limits.items()}
    schema = JointAnglesRequest.model_json_schema()
    schema["properties"]["angles_deg"] = {"description": schema["properties"]["angles_deg"].get("description", ""),
                                          "anyOf": [{"type": "object", "properties": per_joint, "minProperties": 1,
                                                     "additionalProperties": False},
                                                    {"type": "array", "prefixItems": list(per_joint.values()),
                                                     "minItems": len(per_joint), "maxItems": len(per_joint)}]}
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": schema}}}}


@router.post("/joint-angles", response_model=Ok, responses=errors(409, 422), openapi_extra=_joint_angles_body(),
             summary="Interpolate to joint angles (all 30 as a list, or some by name) in `time` s")
def joint_angles(req: JointAnglesRequest, service: ServiceDep) -> Ok:
    if isinstance(req.angles_deg, dict):
        return Ok(message=service.set_some_joint_angles(
            {name: math.radians(v) for name, v in req.angles_deg.items()}, req.time))
    return Ok(message=service.set_joint_angles([math.radians(v) for v in req.angles_deg], req.time))


@router.post("/target-pose", response_model=Ok, responses=errors(404, 409, 422, e404="no such frame"),
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
