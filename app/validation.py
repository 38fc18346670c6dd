"""Request checks against the live model (joint names and limits, scenes, bodies), before the loop sees them."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from app.errors import BadRequest
from app.runtime import Runtime
from app.schemas import MAX_PUSH_FORCE_N, StepRequest
from controller.errors import InvalidCommand
from controller.footsteps import StepParams
from robot.names import JOINT_NAMES, NUM_JOINTS


def require_finite(field: str, values: Iterable[float]) -> None:
    for v in values:
        if not math.isfinite(v):
            raise BadRequest(field, f"must contain finite numbers only (got {v!r})")


def _check_limit(runtime: Runtime, field: str, name: str, value_deg: float) -> None:
    lo, hi = runtime.joint_limits_deg(name)
    if not lo - 1e-9 <= value_deg <= hi + 1e-9:
        raise BadRequest(field, f"{name}={value_deg:g} deg is outside the joint range "
                                f"[{lo:.2f}, {hi:.2f}] deg")


def joint_vector_deg(runtime: Runtime, angles: Sequence[float]) -> np.ndarray:
    """A full 30-joint vector [deg] checked for length, finiteness and joint limits."""
    if len(angles) != NUM_JOINTS:
        raise BadRequest("angles_deg", f"a list must have exactly {NUM_JOINTS} values in JOINT_NAMES order "
                                       f"({', '.join(JOINT_NAMES)}); got {len(angles)}")
    require_finite("angles_deg", angles)
    for name, v in zip(JOINT_NAMES, angles, strict=True):
        _check_limit(runtime, f"angles_deg[{JOINT_NAMES.index(name)}]", name, float(v))
    return np.asarray(angles, dtype=float)


def joint_subset_deg(runtime: Runtime, angles: Mapping[str, float]) -> dict[int, float]:
    """{joint index: angle [deg]} from {joint name: angle [deg]}, checked for names, finiteness, limits."""
    if not angles:
        raise BadRequest("angles_deg", f"give at least one joint; valid joints: {', '.join(JOINT_NAMES)}")
    unknown = [n for n in angles if n not in JOINT_NAMES]
    if unknown:
        raise BadRequest("angles_deg", f"unknown joint name(s) {', '.join(map(repr, unknown))}; "
                                       f"valid joints: {', '.join(JOINT_NAMES)}")
    out = {}
    for name, v in angles.items():
        require_finite(f"angles_deg.{name}", [v])
        _check_limit(runtime, f"angles_deg.{name}", name, float(v))
        out[JOINT_NAMES.index(name)] = float(v)
    return out


def scene_name(runtime: Runtime, scene: str) -> str:
    scenes = runtime.available_scenes()
    if scene not in scenes:
        raise BadRequest("scene", f"unknown scene {scene!r}; available scenes: {', '.join(scenes)}")
    return scene


def body_name(runtime: Runtime, body: str) -> str:
    names = runtime.body_names()
    if body not in names:
        raise BadRequest("body", f"unknown body {body!r}; valid bodies: {', '.join(names)}")
    return body


def push_force(force: Sequence[float]) -> np.ndarray:
    require_finite("force", force)
    f = np.asarray(force, dtype=float)
    magnitude = float(np.linalg.norm(f))
    if magnitude > MAX_PUSH_FORCE_N:
        raise BadRequest("force", f"magnitude {magnitude:.1f} N is above the allowed {MAX_PUSH_FORCE_N:g} N")
    return f


#: StepRequest field -> (StepParams field, unit shown, request value -> StepParams value)
_STEP_FIELDS = {
    "step_height": ("step_height_m", "m", float),
    "step_time": ("step_time_s", "s", float),
    "toe_angle_deg": ("toe_angle_rad", "deg", math.radians),
    "heel_angle_deg": ("heel_angle_rad", "deg", math.radians),
}


def step_params(step: StepRequest | None) -> StepParams | None:
    """The request's swing parameters as a StepParams, each field checked against StepParams' declared
    range (shown in the request's units); None when not given."""
    if step is None:
        return None
    meta = {f.name: f.metadata for f in dataclasses.fields(StepParams)}
    changes = {}
    for name, (param, unit, convert) in _STEP_FIELDS.items():
        value = getattr(step, name)
        if value is None:
            continue
        field = f"step.{name}"
        require_finite(field, [value])
        lo, hi = meta[param].get("min"), meta[param].get("max")
        if unit == "deg":
            lo, hi = (None if v is None else math.degrees(v) for v in (lo, hi))
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise BadRequest(field, f"{value:g} {unit} is outside the allowed range [{lo:g}, {hi:g}] {unit}")
        changes[param] = convert(value)
    try:
        return StepParams(**changes)
    except InvalidCommand as exc:  # a range the table above does not know about
        raise BadRequest("step", str(exc)) from exc
