"""SequencePlayer commands (hrpsys SequencePlayerService in REST form): joint angles, target pose, clear."""

from __future__ import annotations

import numpy as np
from fastapi import APIRouter

from app.deps import RuntimeDep
from app.schemas import JointAnglesRequest, Ok, SequenceStatus, TargetPoseRequest
from app.validation import joint_subset_deg, joint_vector_deg, require_finite
from robot.names import JOINT_NAMES

router = APIRouter(prefix="/api/sequence", tags=["sequence"])

_ERRORS = {422: {"description": "invalid field: the message names it and what is allowed"}}


@router.post("/joint-angles", response_model=Ok, responses=_ERRORS,
             summary="Interpolate to joint angles (all 30 as a list, or some by name) in `time` s")
def joint_angles(req: JointAnglesRequest, runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    time_s = float(req.time)
    if isinstance(req.angles_deg, dict):
        subset = joint_subset_deg(runtime, req.angles_deg)

        def _apply() -> None:
            # one command at one tick boundary; the joints not named keep their motion
            seq = loop.chain["seq"]
            for i, v in subset.items():
                seq.set_joint_angle(JOINT_NAMES[i], float(np.deg2rad(v)), time_s)
    else:
        q_rad = np.deg2rad(joint_vector_deg(runtime, req.angles_deg))

        def _apply() -> None:
            loop.chain["seq"].set_joint_angles(q_rad, time_s)

    runtime.call(_apply)
    return Ok(message=f"interpolating over {time_s:g} s")


@router.post("/target-pose", response_model=Ok, responses=_ERRORS,
             summary="Move a limb's end effector to a pose (relative to `frame` if given) in `time` s")
def target_pose(req: TargetPoseRequest, runtime: RuntimeDep) -> Ok:
    require_finite("pos", req.pos)
    require_finite("rpy_deg", req.rpy_deg)
    loop = runtime.loop
    spec = req.limb if not req.frame else f"{req.limb}:{req.frame}"
    pos = np.asarray(req.pos, dtype=float)
    rpy = np.deg2rad(np.asarray(req.rpy_deg, dtype=float))
    time_s = float(req.time)
    runtime.call(lambda: loop.chain["seq"].set_target_pose(spec, pos, rpy, time_s))
    return Ok(message=f"{spec} moving over {time_s:g} s")


@router.post("/clear", response_model=Ok, summary="Stop the interpolation where it is")
def clear(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    runtime.call(lambda: loop.chain["seq"].clear())
    return Ok(message="sequence cleared")


@router.get("/status", response_model=SequenceStatus, summary="Whether a motion is being interpolated")
def status(runtime: RuntimeDep) -> SequenceStatus:
    loop = runtime.loop
    return SequenceStatus(interpolating=bool(runtime.call(lambda: loop.chain["seq"].is_interpolating())))
