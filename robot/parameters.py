"""HRP-2's parameters as the model generator reads them (robot/data/hrp2_parameters.json): the half-sitting
posture, the joint limits, and how numbers are written in the generated files."""

from __future__ import annotations

import json
import math
from pathlib import Path

from robot.names import JOINT_NAMES, PARAMETERS_JSON


def fmt(x: float) -> str:
    """A number as written in the files: 10 significant digits, no negative zero."""
    s = f"{float(x):.10g}"
    return "0" if s in ("-0", "0") else s


def vec(values) -> str:
    return " ".join(fmt(v) for v in values)


def load_parameters(path: Path = PARAMETERS_JSON) -> dict:
    return json.loads(Path(path).read_text())


def half_sitting_rad(params: dict) -> list[float]:
    return [math.radians(v) for v in half_sitting_deg(params)]


def half_sitting_deg(params: dict | None = None) -> tuple[float, ...]:
    """HRP-2's half-sitting posture [deg], JOINT_NAMES order (the scenes' "home" keyframe)."""
    hs = (params or load_parameters())["half_sitting_deg"]
    return (*hs["RLEG"], *hs["LLEG"], *hs["CHEST"], *hs["HEAD"], *hs["RARM"], *hs["LARM"])


def joint_limits_deg(params: dict | None = None) -> dict[str, tuple[float, float]]:
    """Each joint's (lower, upper) limit [deg], JOINT_NAMES order (as the model files state them)."""
    joints = {j["name"]: j for j in (params or load_parameters())["joints"]}
    return {name: (float(joints[name]["limit_deg"][0]), float(joints[name]["limit_deg"][1])) for name in JOINT_NAMES}
