"""Pydantic request and response bodies of the HTTP API: types, units and ranges of every field."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

MAX_MOTION_TIME_S = 3600.0  # [s]
MAX_PUSH_FORCE_N = 2000.0  # [N]
MAX_PUSH_DURATION_S = 5.0  # [s]
LIMBS = ("rarm", "larm", "rleg", "lleg")


class _Body(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


MotionTime = Field(description="interpolation time [s], in (0, 3600]", gt=0.0, le=MAX_MOTION_TIME_S)


class JointAnglesRequest(_Body):
    angles_deg: dict[str, float] | list[float] = Field(
        description="{joint name: angle [deg]} for some joints, or a list of all 30 angles [deg] in "
                    "JOINT_NAMES order", examples=[{"RARM_JOINT0": -30.0}])
    time: float = MotionTime


class TargetPoseRequest(_Body):
    limb: Literal["rarm", "larm", "rleg", "lleg"] = Field(description="the limb to move", examples=["rarm"])
    frame: str | None = Field(default=None, description="reference link (e.g. BODY); default: the "
                                                        "SequencePlayer's default frame")
    pos: list[float] = Field(description="target position [m] (x, y, z)", min_length=3, max_length=3)
    rpy_deg: list[float] = Field(description="target roll, pitch, yaw [deg]", min_length=3, max_length=3)
    time: float = MotionTime


class ResetRequest(_Body):
    scene: str | None = Field(default=None, description="scene name (GET /api/scenes); default: the current one")


class PushRequest(_Body):
    body: str = Field(description="MuJoCo body name, e.g. BODY", examples=["BODY"])
    force: list[float] = Field(description=f"world-frame force [N], |force| <= {MAX_PUSH_FORCE_N:g}",
                               min_length=3, max_length=3, examples=[[100.0, 0.0, 0.0]])
    duration: float = Field(description=f"push duration [s], in (0, {MAX_PUSH_DURATION_S:g}]",
                            gt=0.0, le=MAX_PUSH_DURATION_S)


class Ok(BaseModel):
    ok: bool = True
    message: str = ""


class SequenceStatus(BaseModel):
    interpolating: bool


class ChainInfo(BaseModel):
    order: list[str]
    chain: str
    timing: dict[str, dict[str, float | int]]
    tick_ms: dict[str, float | int]
    physics_ms: dict[str, float | int]


class ConsoleConfig(BaseModel):
    viewer_port: int | None
    joints: list[str]
    joint_limits_deg: dict[str, list[float]]
    scenes: list[str]
    limbs: list[str] = list(LIMBS)


StateDict = dict[str, Any]
