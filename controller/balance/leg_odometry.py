"""Leg odometry: where the feet are in the world, chained from stance foot to stance foot through the encoders.

The controller's own frame is the gait plan's: the state estimator anchors the measured robot at the planned
soles (a support foot does not slip), so the plan is where the controller believes the feet are. A real foot
lands a little off its planned place (HRP-2 in simulation lands 2-3 mm long per step: 19 mm after a 1.0 m
walk), and nothing in the plan notices. Leg odometry does: while a foot carries the robot it stays where it
is; when the other foot takes the load (both down), the new stance foot's place is the old one's plus the
measured displacement between the two soles (encoders, KalmanFilter attitude). BODY then hangs from the stance
sole by the encoders. The controller's state estimate places the same BODY in the plan's frame, so the pair
gives the plan's frame in the world (`world_from_control`): what turns the controller's coordinates (the feet
frame F, the operational points) into world coordinates that perception and a map can share, and back. A
location turned into the controller's frame by it is the one the controller's own BODY estimate would have
seen, so what a behaviour reaches for is unchanged by the odometry; only the world moves into place. No
simulator state is read; only a foot that slips while it carries the robot is missed (measured: 1 mm after
1.4 m and a 90 deg turn)."""

from __future__ import annotations

import math

from controller.core.types import OdometryEstimate
from controller.kinematics.rotations import wrap_rad

#: [-] the other foot becomes the stance foot once it carries this share of the feet's vertical load ...
SWITCH_LOAD_SHARE = 0.7
#: [rad] ... and its sole is this level (a heel strike or a toe-off is not: its sole origin is off the floor)
FLAT_SOLE_TILT_RAD = math.radians(2.0)
#: [-] a stance foot carrying less than this share is lifting: the other takes over whatever its tilt
LIFT_LOAD_SHARE = 0.1
#: [N] below this total the feet are not on the ground (a fall, a lift): the stance foot stays
MIN_TOTAL_LOAD_N = 40.0


def yaw_of(R) -> float:
    """Yaw [rad] of a rotation given as rows (or an array): the heading of its x axis in the horizontal plane."""
    return math.atan2(R[1][0], R[0][0])


def control_to_world(world_from_control, p) -> tuple[float, float, float]:
    """A point of the controller's frame [m] in the world [m]."""
    x, y, z, yaw = world_from_control
    c, s = math.cos(yaw), math.sin(yaw)
    return x + c * p[0] - s * p[1], y + s * p[0] + c * p[1], z + p[2]


def world_to_control(world_from_control, p) -> tuple[float, float, float]:
    """A point of the world [m] in the controller's frame [m] (the inverse of control_to_world)."""
    x, y, z, yaw = world_from_control
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = p[0] - x, p[1] - y
    return c * dx + s * dy, -s * dx + c * dy, p[2] - z


class LegOdometry:
    """The stance foot's pose in the world, carried over to the other foot at each change of support.

    `update` once per tick with the two soles as the encoders and the attitude estimate place them from BODY
    (world-aligned axes), their measured vertical loads, and BODY as the controller's state estimate places
    it. Until the plan first walks the robot is where the controller's frame has it (it starts where it is
    told it stands), so the two frames agree until a foot lands off its plan."""

    def __init__(self) -> None:
        self.stance: int | None = None
        self.p_stance_world_m = (0.0, 0.0, 0.0)
        self.stance_yaw_rad = 0.0
        self.switches = 0

    def update(self, p_soles_from_body_m, R_soles_world, fz_n, p_body_control_m, walking: bool = False
               ) -> OdometryEstimate:
        """p_soles_from_body_m: the two soles' origins from BODY, world-aligned axes [m] (right, left);
        R_soles_world: their rotations with the attitude estimate's (rows or arrays); fz_n: their vertical
        loads [N]; p_body_control_m: BODY where the controller's state estimate puts it (its frame) [m];
        walking: whether the gait plan walks (steps planned)."""
        first = self.stance is None
        if first:
            self.stance = 0 if fz_n[0] >= fz_n[1] else 1
        if first or (self.switches == 0 and not walking):  # before the first step the robot is where the
            s = self.stance  # controller's frame has it (it starts where it is told it stands, and settles)
            p = p_soles_from_body_m[s]
            self.p_stance_world_m = tuple(float(p_body_control_m[i]) + float(p[i]) for i in range(3))
            self.stance_yaw_rad = yaw_of(R_soles_world[s])
        self._maybe_switch(p_soles_from_body_m, R_soles_world, fz_n, float(p_body_control_m[2]))
        s = self.stance
        # BODY in the world: the encoders from the stance sole, turned by the odometry's heading minus the
        # attitude estimate's; the controller's BODY is the same body in its frame, so the pair places the frame
        dyaw = wrap_rad(self.stance_yaw_rad - yaw_of(R_soles_world[s]))
        c, si = math.cos(dyaw), math.sin(dyaw)
        (px, py, pz), (wx, wy, wz) = p_soles_from_body_m[s], self.p_stance_world_m
        bx, by, bz = wx - (c * px - si * py), wy - (si * px + c * py), wz - pz
        cx, cy, cz = (float(v) for v in p_body_control_m)
        return OdometryEstimate(stance=s, p_stance_world_m=self.p_stance_world_m,
                                stance_yaw_rad=self.stance_yaw_rad, p_body_world_m=(bx, by, bz),
                                world_from_control=(bx - (c * cx - si * cy), by - (si * cx + c * cy), bz - cz, dyaw),
                                switches=self.switches)

    def _maybe_switch(self, p_soles, R_soles, fz, z_body_control_m: float) -> None:
        s = self.stance
        o = 1 - s
        f_s, f_o = max(float(fz[s]), 0.0), max(float(fz[o]), 0.0)
        total = f_s + f_o
        if total < MIN_TOTAL_LOAD_N:
            return
        R_o = R_soles[o]
        level = math.hypot(R_o[0][2], R_o[1][2]) <= math.sin(FLAT_SOLE_TILT_RAD)
        if not ((f_o >= SWITCH_LOAD_SHARE * total and level) or f_s < LIFT_LOAD_SHARE * total):
            return
        # the odometry's heading minus the attitude estimate's, for the same (stance) foot
        dyaw = self.stance_yaw_rad - yaw_of(R_soles[s])
        c, si = math.cos(dyaw), math.sin(dyaw)
        dx, dy = (float(p_soles[o][i]) - float(p_soles[s][i]) for i in range(2))
        x, y, _ = self.p_stance_world_m
        # heights stay the controller's (its plan walks a level floor): chained through the attitude estimate
        # they drifted 0.13 mm a step (its pitch error times the stride), 8 mm over take_can and throw_can
        self.p_stance_world_m = (x + c * dx - si * dy, y + si * dx + c * dy, z_body_control_m + float(p_soles[o][2]))
        self.stance_yaw_rad = wrap_rad(yaw_of(R_o) + dyaw)
        self.stance = o
        self.switches += 1
