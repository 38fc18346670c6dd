"""The operational points of [OP] II-III and the twists commanded at them (Eq. 2-5).

One frame convention for every twist, **the feet frame F**: origin midway between the two soles' reference
positions, z up (the world's vertical), x along the mean yaw of the two soles (forward for the robot).
Linear parts are in m/s, angular parts in rad/s (the HTTP API takes deg/s), both in F's axes.

| point   | linear (F)                     | angular (F)                                   |
|---------|--------------------------------|-----------------------------------------------|
| `rhand` | hand velocity (x, y, z)        | hand angular velocity (x, y, z)               |
| `lhand` | hand velocity (x, y, z)        | hand angular velocity (x, y, z)               |
| `head`  | unused (0)                     | gaze rates: (0, pitch, yaw); pitch > 0 looks down |
| `waist` | (0, 0, height rate)            | BODY (roll, pitch, yaw) rates                 |
| `walk`  | (vx, vy, 0): goVelocity        | (0, 0, vtheta): goVelocity                    |
| `rfoot` | sole velocity (x, y, z)        | unused (0)                                    |
| `lfoot` | sole velocity (x, y, z)        | unused (0)                                    |

The waist's x-y and the COM are never commanded: balance is the controller's ([OP] Eq. 4). A foot point lifts
its sole while standing (refused while walking): the AutoBalancer brings the COM over the other foot first, and
puts the foot down when nothing drives its point any more (controller/operation/foot_point.py).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from controller.core.errors import InvalidCommand
from controller.kinematics.rotations import wrap_rad
from robot.sensors import frozen_array

#: The operational points, in the order they are solved and reported.
POINTS: tuple[str, ...] = ("rhand", "lhand", "head", "waist", "walk", "rfoot", "lfoot")

#: Components a point uses: (linear mask, angular mask); a non-zero unused component is refused.
USED_COMPONENTS: Mapping[str, tuple[tuple[bool, bool, bool], tuple[bool, bool, bool]]] = {
    "rhand": ((True, True, True), (True, True, True)),
    "lhand": ((True, True, True), (True, True, True)),
    "head": ((False, False, False), (False, True, True)),
    "waist": ((False, False, True), (True, True, True)),
    "walk": ((True, True, False), (False, False, True)),
    "rfoot": ((True, True, True), (False, False, False)),
    "lfoot": ((True, True, True), (False, False, False)),
}


@dataclass(frozen=True, slots=True)
class Twist:
    """A velocity at an operational point, in the feet frame F: linear [m/s], angular [rad/s]."""

    linear_m_s: np.ndarray  # (3,)
    angular_rad_s: np.ndarray  # (3,)

    @staticmethod
    def of(linear_m_s=(0.0, 0.0, 0.0), angular_rad_s=(0.0, 0.0, 0.0)) -> Twist:
        return Twist(frozen_array(linear_m_s, (3,)), frozen_array(angular_rad_s, (3,)))

    def __add__(self, other: Twist) -> Twist:
        return Twist.of(self.linear_m_s + other.linear_m_s, self.angular_rad_s + other.angular_rad_s)

    def scaled(self, factor: float) -> Twist:
        return Twist.of(self.linear_m_s * factor, self.angular_rad_s * factor)

    @property
    def is_zero(self) -> bool:
        # on lists: ndarray.any() costs a microsecond, and this is asked a few times per point and tick
        return not (any(self.linear_m_s.tolist()) or any(self.angular_rad_s.tolist()))


ZERO_TWIST = Twist.of()


def check_twist(point: str, twist: Twist) -> None:
    """Raise InvalidCommand naming the point and component when the twist is not one the point takes."""
    if point not in USED_COMPONENTS:
        raise InvalidCommand(f"unknown operational point {point!r}; valid: {list(POINTS)}")
    lin_mask, ang_mask = USED_COMPONENTS[point]
    for part, values, mask in (("linear", twist.linear_m_s.tolist(), lin_mask),
                               ("angular", twist.angular_rad_s.tolist(), ang_mask)):  # (floats: per setpoint)
        if not all(map(math.isfinite, values)):
            raise InvalidCommand(f"{point}.{part}: must be finite, got {values}")
        for axis, value, used in zip("xyz", values, mask, strict=True):
            if value != 0.0 and not used:
                raise InvalidCommand(f"{point}.{part}.{axis}: the {point} point does not use this component "
                                     f"(it must be 0); see controller.operation.points")


def sum_per_point(*contributions: Mapping[str, Twist]) -> dict[str, Twist]:
    """[OP] Eq. 5: xi_ref_i = xi_motion_i + xi_behavior_i (+ ...), per operational point; absent = zero."""
    total: dict[str, Twist] = {}
    for contribution in contributions:
        for point, twist in contribution.items():
            total[point] = total[point] + twist if point in total else twist
    return total


def points_in(names: Iterable[str]) -> tuple[str, ...]:
    """`names` in POINTS order; raises InvalidCommand on an unknown name."""
    names = set(names)
    unknown = sorted(names - set(POINTS))
    if unknown:
        raise InvalidCommand(f"unknown operational point(s) {unknown}; valid: {list(POINTS)}")
    return tuple(p for p in POINTS if p in names)


@dataclass(frozen=True, slots=True)
class PointPose:
    """Where an operational point is, as the controller computes it from its own reference (not the simulator):
    position [m] and rotation (world <- point) in the world frame, and the same in the feet frame F."""

    p_world_m: np.ndarray  # (3,)
    R_world_point: np.ndarray  # (3, 3)
    p_feet_m: np.ndarray  # (3,)
    R_feet_point: np.ndarray  # (3, 3)


@dataclass(frozen=True, slots=True)
class OperationView:
    """What behaviours may read between ticks (the operation layer's view after the last tick).

    Poses are the controller's reference (what it commands), the walking state the AutoBalancer's plan; the
    robot's place in the world is the feet frame F as the gait plan puts it (odometry, not ground truth)."""

    time_s: float
    feet_p_world_m: np.ndarray  # (3,) origin of F in the world
    feet_yaw_rad: float  # yaw of F in the world
    #: "rhand", "lhand", "head" (the gaze origin, x along the gaze), "waist" (BODY), "rfoot", "lfoot" (the soles)
    points: Mapping[str, PointPose]
    gaze_rad: tuple[float, float]  # (pitch, yaw) of the gaze in F; pitch > 0 looks down
    waist_height_m: float  # BODY height above F
    walking: bool
    motion_stopped: bool  # the EmergencyStopper holds (or reverts) the motion: nothing moves until released
    #: the CollisionDetector holds the last collision-free posture (these body pairs would collide): the
    #: poses above are the reference, not where the robot is
    collision_pairs: tuple[tuple[str, str], ...] = ()
    #: the left sole in the right sole's frame: (x [m], y [m], yaw [rad]) as the gait plan has them (half-sitting:
    #: side by side, 0.19 m apart; after an emergency step wherever it landed)
    lsole_from_rsole: tuple[float, float, float] = (0.0, 0.19, 0.0)
    #: "rfoot" or "lfoot" while the AutoBalancer operates that foot (weight going over, lifted, going down, weight
    #: coming back; no walk starts meanwhile), else None
    foot_lifted: str | None = None

    def placed_in_world(self, world_from_control) -> OperationView:
        """This view with its world coordinates (the feet frame F, the points' world poses) moved from the
        controller's frame (the gait plan's) into the world by leg odometry's `world_from_control` (x, y, z
        [m], yaw [rad]; controller.balance.leg_odometry); what is relative to F is unchanged."""
        x, y, z, yaw = (float(v) for v in world_from_control)
        c, s = math.cos(yaw), math.sin(yaw)
        Rz = np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))
        t = np.array((x, y, z))
        points = {name: PointPose(p_world_m=frozen_array(Rz @ pose.p_world_m + t),
                                  R_world_point=frozen_array(Rz @ pose.R_world_point),
                                  p_feet_m=pose.p_feet_m, R_feet_point=pose.R_feet_point)
                  for name, pose in self.points.items()}
        return dataclasses.replace(self, feet_p_world_m=frozen_array(Rz @ self.feet_p_world_m + t),
                                   feet_yaw_rad=wrap_rad(self.feet_yaw_rad + yaw), points=points)
