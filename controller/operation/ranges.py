"""What the operational points take, defined once: the bounds of each point's twist and the walking point's step
ranges. The console's door and schemas, the operator page (GET /api/config) and the AutoBalancer read them here."""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType

from controller.core.errors import InvalidCommand
from controller.operation.points import POINTS, USED_COMPONENTS, Twist, check_twist

#: [m/s] |component| of a hand's, the head's or the waist's linear velocity (the op layer's speed limits act below)
MAX_LINEAR_M_S = 0.5
#: [rad/s] |component| of their angular velocity
MAX_ANGULAR_RAD_S = math.radians(90.0)
#: [m/s] |vx|, |vy| of the walking point and of goVelocity (the gait's stride limits clamp the steps anyway)
WALK_MAX_LINEAR_M_S = 0.5
#: [rad/s] |vtheta| of the walking point and of goVelocity
WALK_MAX_ANGULAR_RAD_S = math.radians(45.0)
#: [m] the walking point's step length limit ([OP] V-A): 0 (step in place) up to this; the stride limits cap it
WALK_MAX_STRIDE_RANGE_M = (0.0, 0.3)
#: [m] the walking point's distance between the feet's centres: HRP-2's soles (0.118 m across their inner
#: edges at 0.19 m) keep >= 2 cm apart at the low end
WALK_FOOT_DISTANCE_RANGE_M = (0.14, 0.30)

#: per point, the bound of each component it uses: (|linear| [m/s], |angular| [rad/s]); the components it does not
#: use (USED_COMPONENTS) must be 0
SPEED_BOUNDS: Mapping[str, tuple[float, float]] = MappingProxyType({
    p: (WALK_MAX_LINEAR_M_S, WALK_MAX_ANGULAR_RAD_S) if p == "walk" else (MAX_LINEAR_M_S, MAX_ANGULAR_RAD_S)
    for p in POINTS})


def component_bounds(point: str) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """|component| allowed at `point`: (linear xyz [m/s], angular xyz [rad/s]), 0 where the point does not use it."""
    (lin, ang), (lin_mask, ang_mask) = SPEED_BOUNDS[point], USED_COMPONENTS[point]
    return (tuple(lin if u else 0.0 for u in lin_mask),  # type: ignore[return-value]
            tuple(ang if u else 0.0 for u in ang_mask))


def check_setpoint(point: str, twist: Twist, max_stride_m: float | None = None,
                   foot_distance_m: float | None = None) -> None:
    """Raise InvalidCommand "<point>.<field>: <why and the allowed range>" when the operator's setpoint is not one
    `point` takes: the components it uses finite and within SPEED_BOUNDS, the others 0, the walking point's step
    ranges. The operation layer's last guard over every setpoint, and the console's door over its own scripts'
    (clients' requests are held to the same bounds by their schema, app/schemas.py)."""
    check_twist(point, twist)  # a known point, finite, the unused components 0
    lin_limit, ang_limit = SPEED_BOUNDS[point]
    for part, values, limit, unit, shown in (("linear", twist.linear_m_s.tolist(), lin_limit, "m/s", float),
                                             ("angular", twist.angular_rad_s.tolist(), ang_limit, "deg/s",
                                              math.degrees)):
        for axis, value in zip("xyz", values, strict=True):
            if abs(value) > limit + 1e-12:  # (the schema's bound in deg/s, converted, may be a last digit over)
                raise InvalidCommand(f"{point}.{part}.{axis}: {shown(value):g} {unit} is outside the allowed range "
                                     f"[{-shown(limit):g}, {shown(limit):g}] {unit}")
    for name, value, (lo, hi) in (("max_stride", max_stride_m, WALK_MAX_STRIDE_RANGE_M),
                                  ("foot_distance", foot_distance_m, WALK_FOOT_DISTANCE_RANGE_M)):
        if value is None:
            continue
        if point != "walk":
            raise InvalidCommand(f"{point}.{name}: is a parameter of the walking point only (point 'walk')")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
            raise InvalidCommand(f"{point}.{name}: {value!r} m is outside the allowed range [{lo:g}, {hi:g}] m")
