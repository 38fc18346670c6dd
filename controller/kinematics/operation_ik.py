"""Whole-body IK of the operation layer ([OP] III): hands, gaze, waist and balance on placo, one QP step per tick."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import pinocchio as pin
import placo

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE, convex_hull_2d, shrink_polygon
from controller.core.errors import InvalidCommand
from controller.core.layer import Params
from controller.core.types import read_only
from controller.kinematics.rotations import (
    quat_xyzw_to_rows,
    quat_xyzw_to_rpy,
    rows_angle_between,
    rows_exp3,
    rows_log3,
    rows_small_log3,
    rpy_to_rows,
)
from controller.kinematics.rotations import rows_mul as _mul
from controller.kinematics.rotations import rows_tmul as _tmul
from controller.kinematics.rotations import rows_tmulv as _tmulv
from robot.names import END_EFFECTORS, JOINT_GROUPS, JOINT_NAMES, URDF

#: The operational points, in the order they are solved and reported.
POINTS: tuple[str, ...] = ("rhand", "lhand", "head", "waist")

#: Why a point did less than it was asked this tick (PointResult.limited).
REACH = "reach"  # out of the workspace, at a singularity, or held back by balance, the torso or another point
JOINT_LIMIT = "joint_limit"  # a joint of its own limb brakes against (or sits at) its position limit
VELOCITY = "velocity"  # a joint of its chain runs at the joint velocity limit
SOLVER = "solver"  # the QP failed; the previous posture is kept

#: Frames in the URDF (robot/hrp2/hrp2.urdf).
HAND_FRAMES = {"rhand": END_EFFECTORS["rarm"], "lhand": END_EFFECTORS["larm"]}
FOOT_FRAMES = (END_EFFECTORS["rleg"], END_EFFECTORS["lleg"])
BODY_FRAME = "BODY"
CHEST_FRAME = "CHEST_LINK1"  # the gaze angles are relative to this link
HEAD_FRAME = "HEAD_LINK1"  # gaze axis: its x axis (the URDF has no camera frames)
NECK_FRAME = "HEAD_LINK0"  # its origin is on both head axes: where the gaze ray starts

_GRIPPERS = (JOINT_NAMES.index("RARM_JOINT6"), JOINT_NAMES.index("LARM_JOINT6"))  # never move a hand frame
_ARM = {"rhand": tuple(i for i in JOINT_GROUPS["rarm"] if i not in _GRIPPERS),
        "lhand": tuple(i for i in JOINT_GROUPS["larm"] if i not in _GRIPPERS)}
_TORSO = JOINT_GROUPS["torso"]
_HEAD = JOINT_GROUPS["head"]
_LEGS = JOINT_GROUPS["rleg"] + JOINT_GROUPS["lleg"]
#: The control joints of each point ([OP] Eq. 1, theta_cl): any at the velocity limit explains a slowdown.
CHAINS: dict[str, tuple[int, ...]] = {"rhand": _TORSO + _ARM["rhand"], "lhand": _TORSO + _ARM["lhand"],
                                      "head": _HEAD, "waist": _LEGS}
#: The point's own limb: one of these braking at its position limit explains a slowdown as "joint_limit";
#: the torso's limits (which extend the hands' workspace) count as the edge of the reach.
LIMBS: dict[str, tuple[int, ...]] = {"rhand": _ARM["rhand"], "lhand": _ARM["lhand"], "head": _HEAD,
                                     "waist": _LEGS}
_COM_TARGET_INSET_M = 0.005  # the COM target stays this much deeper inside than the margin [m]
_TORSO_NAMES = tuple(JOINT_NAMES[i] for i in _TORSO)
_TORSO_SLICE = slice(_TORSO[0], _TORSO[-1] + 1)
assert tuple(range(len(JOINT_NAMES))[_TORSO_SLICE]) == _TORSO


# ---------------------------------------------------------------------------------------------- params


@dataclass(frozen=True)
class OperationIKParams(Params):
    """Weights are placo soft-task weights: a task costs weight * |error|^2, hence [1/m^2] or [1/rad^2]."""

    dt_s: float = field(default=0.005, metadata={"unit": "s", "min": 1e-4, "max": 0.1})
    iterations: int = field(default=1, metadata={"unit": "-", "min": 1, "max": 10})
    # below the SoftErrorLimiter's 3.5 rad/s, which must never have to clip this
    joint_velocity_limit_rad_s: float = field(default=2.0, metadata={"unit": "rad/s", "min": 0.01, "max": 3.5})
    # a step toward a position limit covers at most dt / braking_time of the distance left: a joint slows
    # down within joint_velocity_limit * braking_time (0.05 rad by default) of its limit, never hits it
    joint_limit_braking_time_s: float = field(default=0.025, metadata={"unit": "s", "min": 0.001, "max": 1.0})
    # how fast each point's servo target may move toward its target: the largest step asked of the QP
    hand_speed_m_s: float = field(default=0.5, metadata={"unit": "m/s", "min": 0.001, "max": 5.0})
    hand_angular_speed_rad_s: float = field(default=1.5, metadata={"unit": "rad/s", "min": 0.001, "max": 20.0})
    head_angular_speed_rad_s: float = field(default=1.5, metadata={"unit": "rad/s", "min": 0.001, "max": 20.0})
    waist_speed_m_s: float = field(default=0.2, metadata={"unit": "m/s", "min": 0.001, "max": 5.0})
    waist_angular_speed_rad_s: float = field(default=0.5, metadata={"unit": "rad/s", "min": 0.001, "max": 20.0})
    # points >> balance >> posture: a reachable point ends with no steady-state error
    hand_position_weight: float = field(default=100.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    hand_orientation_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    head_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    waist_height_weight: float = field(default=100.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    waist_orientation_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    # without a waist target, BODY height and orientation are held at the reference's with these
    hold_height_weight: float = field(default=10.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    hold_orientation_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    foot_position_weight: float = field(default=1e5, metadata={"unit": "1/m^2", "min": 1.0, "max": 1e8})
    foot_orientation_weight: float = field(default=1e4, metadata={"unit": "1/rad^2", "min": 1.0, "max": 1e8})
    # balance autonomy ([OP] Eq. 4): COM x-y held where it was when the points became active (moved to
    # the nearest point inside the margin when the support changes), and kept inside the support polygon
    # with a margin by placo's CoM polygon constraint: hard while the COM is inside the margin, soft with
    # this slack weight while it is outside (e.g. after a change of support), so the QP stays feasible
    com_weight: float = field(default=1.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    # ... and toward a COM target the caller gives (e.g. the gait's COG while stepping): followed, not preferred
    com_track_weight: float = field(default=100.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    com_margin_m: float = field(default=0.035, metadata={"unit": "m", "min": 0.0, "max": 0.1})
    com_polygon_weight: float = field(default=1e3, metadata={"unit": "1/m^2", "min": 1.0, "max": 1e8})
    # upper-body mode: the COM may move at most this far (x and y) from where it was at activation, in the
    # BODY frame, so the AutoBalancer's BODY correction for what the arms and torso did stays this small
    com_guard_m: float = field(default=0.04, metadata={"unit": "m", "min": 0.005, "max": 0.2})
    # ... and approaches it as a capture point would: the guard holds c + dc/dt * T (placo's DCM mode, omega =
    # 1/T), so the COM's speed toward an edge is at most (distance left) / T and it comes to rest at the edge
    # smoothly. A plain position bound stopped it within a tick: the torso reversed at ~20 deg/s, the COM
    # estimate moved 9 mm in 50 ms and the capture-point flag stopped the motion (rhand forward, then up)
    com_guard_braking_time_s: float = field(default=0.25, metadata={"unit": "s", "min": 0.01, "max": 5.0})
    # the torso (the redundancy left once points, feet, BODY and COM are set) pulled to the reference
    posture_weight: float = field(default=1e-3, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e3})
    # ... in the upper-body mode, where no COM task holds the torso back: the arms reach first, the torso
    # helps when they cannot. Measured: 1e-3 folds the chest 52 deg to move the left hand sideways; 3e-3
    # keeps rhand 0.20 m forward exact (chest 14 deg) and the left hand at 4 deg; 1.0 keeps the chest still
    # but the right hand reaches only 0.19 m forward
    upper_body_posture_weight: float = field(default=3e-3, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e3})
    # damping of every joint step (placo's QP regularisation): no chattering at singularities (straight arm)
    damping_weight: float = field(default=1e-2, metadata={"unit": "1/rad^2", "min": 1e-9, "max": 1.0})
    # below this fraction of the requested step a point is reported limited
    limited_scale: float = field(default=0.9, metadata={"unit": "-", "min": 0.0, "max": 1.0})
    # a requested step shorter than this is "nothing asked" (scale 1): residuals of competing soft tasks
    scale_deadband_m: float = field(default=2e-4, metadata={"unit": "m", "min": 0.0, "max": 1e-2})
    # rotation counts as (angle x this length) beside translation in the scale ratio
    scale_length_m: float = field(default=0.1, metadata={"unit": "m/rad", "min": 0.001, "max": 10.0})


# ---------------------------------------------------------------------------------------------- targets


def _vector(value, n: int, what: str) -> np.ndarray:
    a = np.array(value, dtype=float)
    if a.shape != (n,) or not np.isfinite(a).all():
        raise InvalidCommand(f"{what} must be {n} finite numbers, got {value!r}")
    return read_only(a)


def _rotation(value, what: str) -> np.ndarray:
    R = np.array(value, dtype=float)
    if R.shape != (3, 3) or not np.isfinite(R).all():
        raise InvalidCommand(f"{what} must be a (3, 3) rotation matrix, got shape {R.shape}")
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0.0:
        raise InvalidCommand(f"{what} is not a rotation (R R^T != I or det < 0); e.g. rpy_to_matrix(rpy)")
    return read_only(R)


@dataclass(frozen=True)
class HandTarget:
    """Pose of a hand frame (rarm_end / larm_end, between the gripper jaws) in the world."""

    p_world: np.ndarray  # (3,) [m]
    R_world: np.ndarray  # (3, 3)

    def __post_init__(self) -> None:
        p, R = _vector(self.p_world, 3, "HandTarget.p_world"), _rotation(self.R_world, "HandTarget.R_world")
        object.__setattr__(self, "p_world", p)
        object.__setattr__(self, "R_world", R)
        object.__setattr__(self, "_floats", (tuple(p.tolist()), tuple(map(tuple, R.tolist()))))

    @classmethod
    def from_rows(cls, p_world: tuple[float, float, float], R_world: tuple) -> HandTarget:
        """trusted() from floats: a position 3-tuple and the rotation's 3 row tuples (kept as `_floats`)."""
        t = object.__new__(cls)
        object.__setattr__(t, "p_world", read_only(np.array(p_world)))
        object.__setattr__(t, "R_world", read_only(np.array(R_world)))
        object.__setattr__(t, "_floats", (p_world, R_world))
        return t

    @classmethod
    def trusted(cls, p_world: np.ndarray, R_world: np.ndarray) -> HandTarget:
        """A target from a pose the caller built as a rotation (e.g. one integrated every tick), unchecked:
        the checks of __init__ cost more than the rest of a tick's bookkeeping."""
        t = object.__new__(cls)
        object.__setattr__(t, "p_world", p_world)
        object.__setattr__(t, "R_world", R_world)
        object.__setattr__(t, "_floats", (tuple(p_world.tolist()), tuple(map(tuple, R_world.tolist()))))
        return t


@dataclass(frozen=True)
class GazeTarget:
    """Where the head looks: yaw/pitch of HEAD_LINK1 relative to CHEST_LINK1, or a point in the world.

    yaw > 0 turns left (about the chest z axis), pitch > 0 looks down (about y, HEAD_JOINT1's sign). With
    `look_at_world`, the gaze axis (HEAD_LINK1 x) points from the neck (HEAD_LINK0 origin) to that point.
    """

    yaw_rad: float = 0.0
    pitch_rad: float = 0.0
    look_at_world: np.ndarray | None = None  # (3,) [m]

    def __post_init__(self) -> None:
        if not (math.isfinite(self.yaw_rad) and math.isfinite(self.pitch_rad)):
            raise InvalidCommand(f"GazeTarget yaw/pitch must be finite [rad], got {self.yaw_rad}, {self.pitch_rad}")
        if self.look_at_world is not None:
            object.__setattr__(self, "look_at_world", _vector(self.look_at_world, 3, "GazeTarget.look_at_world"))

    @classmethod
    def trusted_look_at(cls, look_at_world: np.ndarray) -> GazeTarget:
        """A look-at target the caller computed from finite data (a (3,) float64 array it hands over),
        unchecked: the checks of __init__ are most of its cost, every tick."""
        t = object.__new__(cls)
        object.__setattr__(t, "yaw_rad", 0.0)
        object.__setattr__(t, "pitch_rad", 0.0)
        object.__setattr__(t, "look_at_world", read_only(look_at_world))
        return t


@dataclass(frozen=True)
class WaistTarget:
    """BODY height (its origin's z in the world) and orientation (roll, pitch, yaw in the world)."""

    height_m: float
    rpy_rad: np.ndarray  # (3,)

    def __post_init__(self) -> None:
        if not math.isfinite(self.height_m):
            raise InvalidCommand(f"WaistTarget.height_m must be finite [m], got {self.height_m}")
        rpy = _vector(self.rpy_rad, 3, "WaistTarget.rpy_rad")
        object.__setattr__(self, "rpy_rad", rpy)
        object.__setattr__(self, "_R", rpy_to_rows(*rpy.tolist()))


@dataclass(frozen=True)
class OperationTargets:
    """The operated points; None: not operated (its chain follows the reference posture)."""

    rhand: HandTarget | None = None
    lhand: HandTarget | None = None
    head: GazeTarget | None = None
    waist: WaistTarget | None = None

    @property
    def active(self) -> bool:
        return not (self.rhand is None and self.lhand is None and self.head is None and self.waist is None)


@dataclass(frozen=True)
class FeetPoses:
    """Sole poses (rleg_end / lleg_end) in the world, and which soles carry the robot (support polygon)."""

    p_rsole_world: np.ndarray  # (3,) [m]
    R_rsole_world: np.ndarray  # (3, 3)
    p_lsole_world: np.ndarray  # (3,) [m]
    R_lsole_world: np.ndarray  # (3, 3)
    contact: tuple[bool, bool] = (True, True)  # (right, left)

    def __post_init__(self) -> None:
        object.__setattr__(self, "p_rsole_world", _vector(self.p_rsole_world, 3, "FeetPoses.p_rsole_world"))
        object.__setattr__(self, "p_lsole_world", _vector(self.p_lsole_world, 3, "FeetPoses.p_lsole_world"))
        object.__setattr__(self, "R_rsole_world", _rotation(self.R_rsole_world, "FeetPoses.R_rsole_world"))
        object.__setattr__(self, "R_lsole_world", _rotation(self.R_lsole_world, "FeetPoses.R_lsole_world"))
        contact = tuple(bool(c) for c in self.contact)
        if len(contact) != 2 or not any(contact):
            raise InvalidCommand(f"FeetPoses.contact must be (right, left) with at least one True, got {self.contact}")
        object.__setattr__(self, "contact", contact)
        soles = ((self.p_rsole_world, self.R_rsole_world), (self.p_lsole_world, self.R_lsole_world))
        planar = tuple((float(p[0]), float(p[1]), math.atan2(R[1, 0], R[0, 0])) for p, R in soles)
        object.__setattr__(self, "_planar", planar)  # (x [m], y [m], yaw [rad]) of each sole
        object.__setattr__(self, "_keys", tuple((*p.tolist(), *R.ravel().tolist()) for p, R in soles))


# ---------------------------------------------------------------------------------------------- results


class PointResult(NamedTuple):
    """What an operational point achieved this tick (a NamedTuple: several are built every tick).

    `scale` in [0, 1]: the part of this tick's requested step (servo target minus the pose before the
    solve; rotation weighted by scale_length_m) the point achieved along the requested direction; 1 when
    the request is under the deadband. A caller integrating velocity commands multiplies them by it (the
    point slows down and keeps its direction) and, whenever `limited` is set, clamps its target to the
    achieved pose `T_world`, so its target never runs away from the robot.
    """

    T_world: np.ndarray  # (4, 4) achieved frame pose (hands: rarm_end/larm_end, head: HEAD_LINK1, waist: BODY)
    error_m: float  # |target - achieved| position [m] (head: 0; waist: height)
    error_rad: float  # rotation angle from achieved to target [rad] (head: between the gaze axes)
    scale: float  # [0, 1]
    limited: str | None  # None, REACH, JOINT_LIMIT, VELOCITY or SOLVER

    @property
    def p_world(self) -> np.ndarray:
        return self.T_world[:3, 3]

    @property
    def R_world(self) -> np.ndarray:
        return self.T_world[:3, :3]


@dataclass(frozen=True, slots=True)
class OperationIKResult:
    q_rad: np.ndarray  # (30,) JOINT_NAMES order [rad]
    base_pos_world: np.ndarray  # (3,) BODY [m]
    base_rpy_rad: np.ndarray  # (3,) BODY roll, pitch, yaw [rad]
    points: Mapping[str, PointResult]  # the active points
    active: bool  # False: nothing operated; the inputs are returned as they are
    ok: bool = True  # False: the QP failed and the previous posture was kept
    com_world: np.ndarray | None = None  # (3,) [m]
    com_margin_m: float | None = None  # COM x-y to the nearest support-polygon edge [m], < 0 outside


_NO_POINTS: Mapping[str, PointResult] = MappingProxyType({})


# ---------------------------------------------------------------------------------------- 3-vectors on floats
# Vectors as 3-tuples (rotations as 3 row tuples, in controller.kinematics.rotations): on 3x3 data plain floats
# are several times faster than numpy's per-call overhead, and this runs a few times per point per 5 ms tick.


def _sub(a, b):
    return a[0] - b[0], a[1] - b[1], a[2] - b[2]


def _dot(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _clip(v, limit: float):
    """The 3-vector v shortened to at most `limit` (same direction)."""
    return _clip2(v, limit)[0]


def _clip2(v, limit: float):
    """(v shortened to at most `limit`, whether it was longer)."""
    x, y, z = v
    n2 = x * x + y * y + z * z
    if n2 <= limit * limit:
        return (x, y, z), False
    k = limit / math.sqrt(n2)
    return (x * k, y * k, z * k), True


def _split(T_rows):
    """(position, rotation rows) of a 4x4 pose given as nested lists."""
    r0, r1, r2 = T_rows[0], T_rows[1], T_rows[2]
    return (r0[3], r1[3], r2[3]), ((r0[0], r0[1], r0[2]), (r1[0], r1[1], r1[2]), (r2[0], r2[1], r2[2]))


class _Polygon:
    """The support polygon of the soles in contact: placo's clockwise vertex list, the inward edge lines
    (for the margin), and the polygon shrunk by `inset_m` (where the COM target must be). Plain floats:
    it is rebuilt at every change of support."""

    def __init__(self, soles, inset_m: float) -> None:
        """soles: ((x [m], y [m], yaw [rad]), FootRectangle) of each sole in contact."""
        corners = []
        for (x, y, yaw), rect in soles:
            c, s = math.cos(yaw), math.sin(yaw)
            for fx, fy in ((-rect.rear_m, -rect.right_m), (rect.front_m, -rect.right_m),
                           (rect.front_m, rect.left_m), (-rect.rear_m, rect.left_m)):
                corners.append((x + c * fx - s * fy, y + s * fx + c * fy))
        ccw = [tuple(v) for v in convex_hull_2d(corners).tolist()]  # counter-clockwise
        self.ccw = ccw
        self.clockwise = [np.array(v) for v in ccw[::-1]]
        self.edges = _edges(ccw)  # (inward normal x, y, offset): inside where n . p >= offset
        # every edge moved in by the margin: the new vertices are where consecutive moved edges meet; valid
        # while no edge vanishes (each keeps its direction), else the general clipping does it
        moved = [(nx, ny, off + inset_m) for nx, ny, off in self.edges]
        safe = []
        for (ax, ay, ad), (bx, by, bd) in zip(moved[-1:] + moved[:-1], moved, strict=True):
            det = ax * by - ay * bx
            safe.append(((ad * by - bd * ay) / det, (ax * bd - bx * ad) / det))
        n = len(safe)
        keeps_direction = all(
            (safe[(i + 1) % n][0] - safe[i][0]) * (ccw[(i + 1) % n][0] - ccw[i][0])
            + (safe[(i + 1) % n][1] - safe[i][1]) * (ccw[(i + 1) % n][1] - ccw[i][1]) > 0.0 for i in range(n))
        if not keeps_direction:
            clipped = shrink_polygon(np.array(ccw), inset_m)
            safe = [tuple(v) for v in clipped.tolist()] or [
                (sum(v[0] for v in ccw) / len(ccw), sum(v[1] for v in ccw) / len(ccw))]
        self.safe = safe
        self.safe_edges = _edges(safe) if len(safe) >= 3 else []

    def margin(self, x: float, y: float) -> float:
        """Smallest distance to an edge line [m]: the distance to the boundary inside, < 0 outside."""
        return min(nx * x + ny * y - off for nx, ny, off in self.edges)

    def nearest_safe(self, x: float, y: float) -> tuple[float, float]:
        """(x, y) if it is inside the margin, else the nearest point of the shrunk polygon."""
        if not self.safe_edges:
            return self.safe[0]
        if min(nx * x + ny * y - off for nx, ny, off in self.safe_edges) >= 0.0:
            return x, y
        best, best_d2 = self.safe[0], math.inf
        v = self.safe
        for (ax, ay), (bx, by) in zip(v, v[1:] + v[:1], strict=True):
            dx, dy = bx - ax, by - ay
            t = max(0.0, min(1.0, ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)))
            px, py = ax + t * dx, ay + t * dy
            d2 = (px - x) ** 2 + (py - y) ** 2
            if d2 < best_d2:
                best, best_d2 = (px, py), d2
        return best


class _GuardBox:
    """The upper-body mode's COM guard: a square of half-side `half_m` around (x, y), as placo's clockwise
    vertex list, with the margin to its edges."""

    def __init__(self, x: float, y: float, half_m: float) -> None:
        ccw = [(x - half_m, y - half_m), (x + half_m, y - half_m), (x + half_m, y + half_m), (x - half_m, y + half_m)]
        self.clockwise = [np.array(v) for v in ccw[::-1]]
        self.edges = _edges(ccw)
        self._box = (x - half_m, x + half_m, y - half_m, y + half_m)

    def margin(self, x: float, y: float) -> float:
        """min over the edges of n . p - offset, which for this axis-aligned box is exactly the distances to
        its four sides (asked twice a tick: no generator)."""
        x0, x1, y0, y1 = self._box
        return min(y - y0, x1 - x, y1 - y, x - x0)


def _edges(ccw) -> list[tuple[float, float, float]]:
    out = []
    for (ax, ay), (bx, by) in zip(ccw, ccw[1:] + ccw[:1], strict=True):
        length = math.hypot(bx - ax, by - ay)
        nx, ny = -(by - ay) / length, (bx - ax) / length
        out.append((nx, ny, nx * ax + ny * ay))
    return out


# ---------------------------------------------------------------------------------------------- points


class _Point:
    """One operational point: its placo tasks, its servo step toward its target, what it achieved."""

    name = ""

    def __init__(self) -> None:
        self.tasks: tuple = ()
        self.requested: tuple = ()
        self.chain_list = CHAINS[self.name]
        self.limb_set = frozenset(LIMBS[self.name])
        self.bound_rows: tuple | None = None  # the chain's joint limits, as OperationIK._limit_reason reads them

    def add(self, solver) -> None:  # noqa: B027 - the waist has no task of its own
        """Create the placo tasks (the point became active)."""

    def remove(self, solver) -> None:
        for task in self.tasks:
            solver.remove_task(task)
        self.tasks = ()

    def configure(self, p: OperationIKParams) -> None:  # noqa: B027
        """Task weights from the parameters."""

    @staticmethod
    def scale(dz_ach: float, dz_req: float, dp_ach, dp_req, w_ach, w_req, p: OperationIKParams) -> float:
        """The achieved step projected on the requested one, as a fraction of it, in [0, 1]: translation
        (a height dz and/or a 3-vector dp [m]) and rotation (w [rad], counted as angle x scale_length_m);
        a request under the deadband is nothing asked (1)."""
        L2 = p.scale_length_m * p.scale_length_m
        rr = dz_req * dz_req + L2 * _dot(w_req, w_req)
        ar = dz_ach * dz_req + L2 * _dot(w_ach, w_req)
        if dp_req is not None:
            rr += _dot(dp_req, dp_req)
            ar += _dot(dp_ach, dp_req)
        if rr <= p.scale_deadband_m * p.scale_deadband_m:
            return 1.0
        return min(1.0, max(0.0, ar / rr))


class _Hand(_Point):
    def __init__(self, name: str) -> None:
        self.name = name
        super().__init__()
        self.frame = HAND_FRAMES[name]
        self.T: np.ndarray | None = None  # pose after the last solve, and as nested lists
        self.T_rows: list | None = None
        self.T_fk = -1  # the forward-kinematics pass it was read in
        self.servo_key: tuple = (None, None)  # the target the position / orientation tasks hold, if unclipped

    def add(self, solver) -> None:
        frame = solver.add_frame_task(self.frame, np.eye(4))
        self.tasks = (frame.position(), frame.orientation())
        self.servo_key = (None, None)

    def configure(self, p: OperationIKParams) -> None:
        self.tasks[0].configure(f"{self.name}_position", "soft", p.hand_position_weight)
        self.tasks[1].configure(f"{self.name}_orientation", "soft", p.hand_orientation_weight)

    def servo(self, ik: OperationIK, target: HandTarget) -> None:
        p, dt = ik.params, ik.params.dt_s
        rows = self.T_rows if self.T_fk == ik.fk_count else ik.robot.get_T_world_frame(self.frame).tolist()
        p0, R0 = _split(rows)
        pt, Rt = target._floats
        dp, clipped_p = _clip2(_sub(pt, p0), p.hand_speed_m_s * dt)
        w, clipped_w = _clip2(rows_log3(_tmul(R0, Rt)), p.hand_angular_speed_rad_s * dt)
        # the target itself when it is within one step (no conversion), else one step toward it
        if clipped_p:
            self.tasks[0].target_world = np.array((p0[0] + dp[0], p0[1] + dp[1], p0[2] + dp[2]))
        elif self.servo_key[0] is not target:
            self.tasks[0].target_world = target.p_world
        if clipped_w:
            self.tasks[1].R_world_frame = np.array(_mul(R0, rows_exp3(w)))
        elif self.servo_key[1] is not target:
            self.tasks[1].R_world_frame = target.R_world
        self.servo_key = (None if clipped_p else target, None if clipped_w else target)
        self.requested = (p0, R0, dp, w)

    def result(self, ik: OperationIK, target: HandTarget) -> tuple:
        T = self.T = ik.robot.get_T_world_frame(self.frame)
        rows = self.T_rows = T.tolist()
        self.T_fk = ik.fk_count
        p1, R1 = _split(rows)
        p0, R0, dp, w = self.requested
        pt, Rt = target._floats
        scale = self.scale(0.0, 0.0, _sub(p1, p0), dp, rows_small_log3(_tmul(R0, R1)), w, ik.params)
        error_m = math.dist(pt, p1)
        return T, error_m, rows_angle_between(R1, Rt), scale


class _Head(_Point):
    """Gaze. HEAD_LINK1 is exactly Rz(HEAD_JOINT0) Ry(HEAD_JOINT1) in CHEST_LINK1 (no origin rotations in the
    URDF), so the chest-relative gaze angles are the two head joint targets: a two-joint task is the exact
    gaze task, and cheaper than an orientation task."""

    name = "head"
    _JOINTS = tuple(JOINT_NAMES[i] for i in _HEAD)

    def add(self, solver) -> None:
        self.tasks = (solver.add_joints_task(),)
        self.goal: tuple[float, float] | None = None

    def configure(self, p: OperationIKParams) -> None:
        self.tasks[0].configure("head", "soft", p.head_weight)

    def servo(self, ik: OperationIK, target: GazeTarget) -> None:
        q_yaw, q_pitch = ik.head_angles()
        if target.look_at_world is not None:
            # the point in the chest frame: R_world_neck = R_world_chest Rz(q_yaw), from the neck's origin
            p_neck, R_neck = _split(ik.robot.get_T_world_frame(NECK_FRAME).tolist())
            d = _tmulv(R_neck, _sub(target.look_at_world.tolist(), p_neck))
            c, s = math.cos(q_yaw), math.sin(q_yaw)
            dx, dy, dz = c * d[0] - s * d[1], s * d[0] + c * d[1], d[2]
            yaw, pitch = math.atan2(dy, dx), math.atan2(-dz, math.hypot(dx, dy))
        else:
            yaw, pitch = target.yaw_rad, target.pitch_rad
        (d_yaw, d_pitch, _), _ = _clip2((yaw - q_yaw, pitch - q_pitch, 0.0),
                                        ik.params.head_angular_speed_rad_s * ik.params.dt_s)
        goal = (q_yaw + d_yaw, q_pitch + d_pitch)
        if goal != self.goal:
            task = self.tasks[0]
            for joint, value, last in zip(self._JOINTS, goal, self.goal or (None, None), strict=True):
                if value != last:  # one joint at a time: no dict to convert
                    task.set_joint(joint, value)
            self.goal = goal
        self.requested = (q_yaw, q_pitch, d_yaw, d_pitch, yaw, pitch)

    def result(self, ik: OperationIK, target: GazeTarget) -> tuple:
        yaw1, pitch1 = ik.head_angles()
        q_yaw, q_pitch, d_yaw, d_pitch, yaw, pitch = self.requested
        scale = self.scale(0.0, 0.0, None, None, (yaw1 - q_yaw, pitch1 - q_pitch, 0.0), (d_yaw, d_pitch, 0.0),
                           ik.params)
        # the angle between the achieved and the wanted gaze axes
        c = (math.cos(yaw1 - yaw) * math.cos(pitch1) * math.cos(pitch) + math.sin(pitch1) * math.sin(pitch))
        return ik.robot.get_T_world_frame(HEAD_FRAME), 0.0, math.acos(max(-1.0, min(1.0, c))), scale


class _Waist(_Point):
    """BODY height and orientation. Its tasks always exist: they hold the reference when it is not operated."""

    name = "waist"

    def servo(self, ik: OperationIK, target: WaistTarget) -> None:
        p, dt = ik.params, ik.params.dt_s
        z0, R0 = ik.base_pose()
        step = p.waist_speed_m_s * dt
        dz = max(-step, min(step, target.height_m - z0))
        w = _clip(rows_log3(_tmul(R0, target._R)), p.waist_angular_speed_rad_s * dt)
        ik.body_z_task.target_world = np.array((0.0, 0.0, z0 + dz))
        ik.body_R_task.R_world_frame = np.array(_mul(R0, rows_exp3(w)))
        self.requested = (z0, R0, dz, w)

    def result(self, ik: OperationIK, target: WaistTarget) -> tuple:
        z1, R1 = ik.base_pose()
        z0, R0, dz, w = self.requested
        scale = self.scale(z1 - z0, dz, None, None, rows_small_log3(_tmul(R0, R1)), w, ik.params)
        x, y, _ = ik.q[:3].tolist()
        T = np.array((R1[0] + (x,), R1[1] + (y,), R1[2] + (z1,), (0.0, 0.0, 0.0, 1.0)))
        return T, abs(target.height_m - z1), rows_angle_between(R1, target._R), scale


# ---------------------------------------------------------------------------------------------- solver


class OperationIK:
    """placo KinematicsSolver on the HRP-2 URDF, warm-started between ticks (one QP step per tick).

    Every tick: the chains nobody operates follow the reference joint angles (rate-limited, masked out of
    the QP); the legs, the floating base and the operated chains solve one step: soles on their poses
    (soft, very high weight), each active point toward a servo target one bounded step from its pose
    toward its target, BODY height and orientation on the waist target (or held at the reference's), COM
    x-y held where it was at activation and, near the edge, inside the support polygon with a margin, the
    torso toward the reference posture. Hard: per-joint step bounds (velocity limit, braking near the
    position limits). A tick without active points returns its inputs untouched, without solving.
    """

    def __init__(self, urdf_path=URDF, params: OperationIKParams | None = None, upper_body: bool = False) -> None:
        """upper_body=True: the floating base and the legs stay where the caller puts them (the
        AutoBalancer owns them and balance); only the arms, torso and head solve, with no foot, BODY or COM
        task, the COM kept within com_guard_m of where it was at activation by a guard constraint; no
        waist point (the caller moves BODY itself)."""
        self.params = params or OperationIKParams()
        self.upper_body = upper_body
        self.robot = placo.RobotWrapper(str(urdf_path), placo.Flags.ignore_collisions)
        robot = self.robot
        missing = sorted(set(JOINT_NAMES) - set(robot.joint_names()))
        if missing:
            raise InvalidCommand(f"URDF {urdf_path} lacks joints {missing}; it must have all of JOINT_NAMES")
        self.nq = robot.model.nq
        #: where each JOINT_NAMES joint sits in placo's configuration (placo orders the joints by name)
        self.idx_q = np.array([robot.get_joint_offset(n) for n in JOINT_NAMES])
        self.q_lower = robot.model.lowerPositionLimit[self.idx_q].copy()
        self.q_upper = robot.model.upperPositionLimit[self.idx_q].copy()
        self._lower, self._upper = self.q_lower.tolist(), self.q_upper.tolist()
        self._idx_q_list = self.idx_q.tolist()
        self._head_q = tuple(int(self.idx_q[i]) for i in _HEAD)
        self.solver = placo.KinematicsSolver(robot)
        solver = self.solver
        solver.enable_joint_limits(False)  # replaced by the step bounds (velocity limit and braking)
        solver.enable_velocity_limits(False)
        if upper_body:
            solver.mask_fbase(True)
            self._feet, self._foot_tasks = [], []
            self.body_z_task = self.body_R_task = self._com = None
        else:
            self._feet = [solver.add_frame_task(f, np.eye(4)) for f in FOOT_FRAMES]
            self._foot_tasks = [(t.position(), t.orientation()) for t in self._feet]
            self.body_z_task = solver.add_position_task(BODY_FRAME, np.zeros(3))
            self.body_z_task.mask.set_axises("z")
            self.body_R_task = solver.add_orientation_task(BODY_FRAME, np.eye(3))
            self._com = solver.add_com_task(np.zeros(3))
            self._com.mask.set_axises("xy")
        self._base_key: tuple | None = None  # upper-body mode: the base pose last written
        self._base_rows: tuple = (None, None)  # (base key, its rotation rows)
        self._base_arg: tuple = (None, None, None)  # (base position, rpy arrays, their key): last read
        self._base_arrays: tuple = (None, None, None)  # (base key, position, rpy): the result's arrays
        self._masked_settled: list | None = None  # the reference the masked chains have reached
        self._com_polygon = None  # the constraint (whole-body: while the COM is near the edge; upper body: the guard)
        self._guard_base: tuple | None = None  # upper-body mode: the base pose the guard's world box is for
        self._com_tracking = False  # the caller gives the COM target (com_track_weight)
        self._com_polygon_hard = True
        self._polygon: _Polygon | None = None
        self._polygon_key: tuple | None = None
        self._bounds = None  # step bounds on the free joints, rebuilt with them
        self._posture = None
        self._posture_ref: list[float] | None = None
        self._hold: tuple | None = None  # the reference BODY height and rpy last written to the hold tasks
        self._points: dict[str, _Point] = {"rhand": _Hand("rhand"), "lhand": _Hand("lhand"),
                                           "head": _Head(), "waist": _Waist()}
        self._active: tuple[str, ...] = ()
        self._inactive = (True, True, True, True)  # per point of POINTS: not operated
        self._masked: list[tuple[int, int]] = []  # (JOINT_NAMES index, placo index) out of the QP
        self._free = np.arange(len(JOINT_NAMES))
        self._seeded = False
        self.q = np.zeros(self.nq)  # placo's configuration, as last written or solved
        self.fk_count = 0  # forward-kinematics passes so far: what cached poses refer to
        self._com_cache: tuple[int, list] = (-1, [0.0, 0.0, 0.0])
        self._feet_poses: FeetPoses | None = None
        self._com_ref = (0.0, 0.0)  # COM x-y target before the margin [m]: at activation, or the caller's
        self._configure_weights()

    def __repr__(self) -> str:
        return f"OperationIK(nq={self.nq}, active={list(self._active)}, params={self.params})"

    # ---- configuration ---------------------------------------------------------------------------
    def set_params(self, params: OperationIKParams) -> None:
        self.params = params
        self._configure_weights()
        if self._active:
            self._set_active(self._active, rebuild=True)  # the bounds' braking gain

    def _configure_weights(self) -> None:
        p = self.params
        self.solver.problem.regularization = p.damping_weight
        if self.upper_body:
            for name in self._active:
                self._points[name].configure(p)
            if self._posture is not None:
                self._posture.configure("posture", "soft", p.upper_body_posture_weight)
            if self._com_polygon is not None:
                self.solver.dt = p.dt_s
                self._com_polygon.omega = 1.0 / p.com_guard_braking_time_s
            if self._com_polygon is not None:
                self._com_polygon.margin = 0.0
                self._configure_com_polygon(True)
            self._polygon_key = None
            return
        for side, task in zip(("rfoot", "lfoot"), self._feet, strict=True):
            task.configure(side, "soft", p.foot_position_weight, p.foot_orientation_weight)
        self._com.configure("com", "soft", p.com_track_weight if self._com_tracking else p.com_weight)
        if "waist" in self._active:
            self.body_z_task.configure("waist_height", "soft", p.waist_height_weight)
            self.body_R_task.configure("waist_orientation", "soft", p.waist_orientation_weight)
        else:
            self.body_z_task.configure("hold_height", "soft", p.hold_height_weight)
            self.body_R_task.configure("hold_orientation", "soft", p.hold_orientation_weight)
        for name in self._active:
            self._points[name].configure(p)
        if self._posture is not None:
            self._posture.configure("posture", "soft", p.posture_weight)
        if self._com_polygon is not None:
            self._com_polygon.margin = p.com_margin_m
            self._configure_com_polygon(self._com_polygon_hard)
        self._polygon_key = None  # the margin polygon is rebuilt with the next feet

    def _set_active(self, active: tuple[str, ...], rebuild: bool = False) -> None:
        """Add and remove point tasks; mask the chains nobody operates; bounds and posture on the rest."""
        solver = self.solver
        for name in set(self._active) - set(active):
            self._points[name].remove(solver)
        for name in active:
            if name not in self._active:
                self._points[name].add(solver)
        self._active = active
        self._inactive = tuple(n not in active for n in POINTS)
        hands = [n for n in ("rhand", "lhand") if n in active]
        free = (set() if self.upper_body else set(_LEGS)) | (set(_TORSO) if hands else set())
        free |= set(_HEAD) if "head" in active else set()
        for name in hands:
            free |= set(_ARM[name])
        for i, _ in self._masked:
            solver.unmask_dof(JOINT_NAMES[i])
        self._masked = [(i, int(self.idx_q[i])) for i in range(len(JOINT_NAMES)) if i not in free]
        for i, _ in self._masked:
            solver.mask_dof(JOINT_NAMES[i])
        self._free = np.array(sorted(free), dtype=int)
        # step bounds as A q <= b on the free joints, rows [upper bounds; lower bounds], in the form
        # b = min((1 - k) Q + K, Q + step) with Q = [q; -q], K = k [upper; -lower], k = dt / braking time
        free_q = self.idx_q[self._free]
        n = len(free_q)
        self._bound_q = np.concatenate((free_q, free_q))
        self._bound_sign = np.concatenate((np.ones(n), -np.ones(n)))
        k = min(1.0, self.params.dt_s / self.params.joint_limit_braking_time_s)  # k <= 1: never past a limit
        self._bound_k = k
        self._bound_K = k * np.concatenate((self.q_upper[self._free], -self.q_lower[self._free]))
        if self._bounds is not None:
            solver.remove_constraint(self._bounds)
        self._bound_sign_k = (1.0 - k) * self._bound_sign
        self._bound_step = (None, None)
        self._masked_settled = None
        A = np.zeros((2 * n, self.nq))
        A[np.arange(2 * n), self._bound_q] = self._bound_sign
        self._bounds = solver.add_joint_space_half_spaces_constraint(A, np.zeros(2 * n))
        self._bounds.configure("step_bounds", "hard", 1.0)
        # posture on the torso: the redundancy left once hands, feet, BODY and COM are set
        if not rebuild:
            if self._posture is not None:
                solver.remove_task(self._posture)
                self._posture = None
            if hands:
                self._posture = solver.add_joints_task()
            self._posture_ref = None
        self._configure_weights()

    def _configure_com_polygon(self, hard: bool) -> None:
        if hard:
            self._com_polygon.configure("com_polygon", "hard", 1.0)
        else:
            self._com_polygon.configure("com_polygon", "soft", self.params.com_polygon_weight)
        self._com_polygon_hard = hard

    # ---- joint order and state -------------------------------------------------------------------------
    def to_placo(self, q_rad, base_pos_world, R_world_base) -> np.ndarray:
        """(nq,) placo configuration from JOINT_NAMES-ordered joints [rad] and the BODY pose."""
        q = np.zeros(self.nq)
        q[:3] = base_pos_world
        q[3:7] = pin.Quaternion(np.asarray(R_world_base, dtype=float)).coeffs()  # x, y, z, w
        q[self.idx_q] = q_rad
        return q

    def from_placo(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(joints (30,) in JOINT_NAMES order [rad], BODY position (3,) [m], BODY rotation (3, 3))."""
        return q[self.idx_q].copy(), q[:3].copy(), np.array(quat_xyzw_to_rows(*q[3:7].tolist()))

    def head_angles(self) -> tuple[float, float]:
        """(HEAD_JOINT0, HEAD_JOINT1) [rad] in the current configuration."""
        return float(self.q[self._head_q[0]]), float(self.q[self._head_q[1]])

    def base_pose(self) -> tuple[float, tuple]:
        """(BODY height [m], BODY rotation rows) in the current configuration."""
        return float(self.q[2]), quat_xyzw_to_rows(*self.q[3:7].tolist())

    def _forward_kinematics(self) -> None:
        self.robot.update_kinematics()
        self.fk_count += 1

    def _com_now(self) -> list:
        if self._com_cache[0] != self.fk_count:
            self._com_cache = (self.fk_count, self.robot.com_world().tolist())
        return self._com_cache[1]

    # ---- per tick ----------------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the warm start: the next active solve starts from its inputs."""
        self._seeded = False

    def warm_start(self, q: np.ndarray) -> None:
        """Continue from the placo configuration `q` (nq,) (a copy of an earlier `self.q`), e.g. the
        posture an emergency stop reverted to; the next solve steps from there instead of its inputs."""
        self.q = np.array(q, dtype=float)
        self.robot.state.q = self.q
        self._forward_kinematics()
        self._seeded = True
        self._masked_settled = None

    def solve(self, q_rad: np.ndarray, base_pos_world: np.ndarray, base_rpy_rad: np.ndarray,
              targets: OperationTargets, feet: FeetPoses | None = None,
              com_xy_world: np.ndarray | None = None) -> OperationIKResult:
        """One tick: the posture realising `targets` one step further, from the last solution.

        q_rad (30,), base pose: the upstream reference. It seeds the warm start after an idle tick; the
        chains nobody operates and the torso posture follow it; BODY height and orientation are held at it
        without a waist target. feet: sole poses and contacts; None keeps the soles where the reference
        had them when the points became active. com_xy_world (2,) [m]: where to hold the COM (e.g. the
        AutoBalancer's planned COG, so that its BODY correction downstream stays small); None: where it
        was when the points became active. Either is moved into the support polygon's margin if outside.
        """
        if not targets.active:  # idle: a pass-through; the next active tick seeds afresh
            self._seeded = False
            return OperationIKResult(q_rad=q_rad, base_pos_world=base_pos_world, base_rpy_rad=base_rpy_rad,
                                     points=_NO_POINTS, active=False)
        p = self.params
        robot = self.robot
        q_ref = np.asarray(q_rad, dtype=float).tolist()
        lower, upper = self._lower, self._upper
        seeding = not self._seeded
        seeding_base = False
        if seeding:
            q_clip = np.minimum(np.maximum(np.asarray(q_rad, dtype=float), self.q_lower), self.q_upper)
            self.q = self.to_placo(q_clip, base_pos_world, rpy_to_rows(*np.asarray(base_rpy_rad).tolist()))
            self._hold = None
        elif self.upper_body:  # the base where the caller has it now (the AutoBalancer moves it)
            key = self._base_key_of(base_pos_world, base_rpy_rad)
            if key != self._base_key:
                self.q[:3] = key[:3]
                self.q[3:7] = pin.Quaternion(np.array(rpy_to_rows(*key[3:]))).coeffs()
                self._base_key = None  # written below with the masked chains' forward kinematics
                seeding_base = True
        if self.upper_body and targets.waist is not None:
            raise InvalidCommand("OperationIK(upper_body=True) has no waist point: the caller moves BODY itself")
        active = self._active
        inactive = (targets.rhand is None, targets.lhand is None, targets.head is None, targets.waist is None)
        if inactive != self._inactive:
            active = tuple(n for n in POINTS if getattr(targets, n) is not None)
            self._set_active(active)
        q = self.q
        step = p.joint_velocity_limit_rad_s * p.dt_s
        # the chains nobody operates, and the grippers: toward the reference, no faster than the limit
        moved = seeding or seeding_base
        if seeding or q_ref != self._masked_settled:  # (settled on this reference: nothing left to move)
            settled = True
            for i, j in self._masked:
                d = min(upper[i], max(lower[i], q_ref[i])) - q[j]
                if d:
                    q[j] += d if -step <= d <= step else (step if d > 0.0 else -step)
                    moved = True
                    settled = False
            self._masked_settled = q_ref if settled else None
        if moved:
            robot.state.q = q
            self._forward_kinematics()
        if self.upper_body:
            return self._solve_upper_body(targets, q, q_ref, seeding, base_pos_world, base_rpy_rad)
        if seeding:
            self._com_ref = tuple(self._com_now()[:2])
            if feet is None:  # the soles stay where the reference has them
                Tr, Tl = (robot.get_T_world_frame(f) for f in FOOT_FRAMES)
                feet = FeetPoses(Tr[:3, 3], Tr[:3, :3], Tl[:3, 3], Tl[:3, :3])
            self._polygon_key = None
        if feet is not None and feet is not self._feet_poses or self._polygon_key is None:
            self._set_feet(feet if feet is not None else self._feet_poses)
        if (com_xy_world is not None) != self._com_tracking:
            self._com_tracking = com_xy_world is not None
            self._com.configure("com", "soft", p.com_track_weight if self._com_tracking else p.com_weight)
        if com_xy_world is not None:
            com_ref = (float(com_xy_world[0]), float(com_xy_world[1]))
            if com_ref != self._com_ref:
                self._com_ref = com_ref
                self._set_com_target()
        self._seeded = True
        if self._posture is not None:  # torso posture toward the reference
            torso = q_ref[_TORSO_SLICE]
            if torso != self._posture_ref:
                self._posture.set_joints({n: min(upper[i], max(lower[i], q_ref[i]))
                                          for n, i in zip(_TORSO_NAMES, _TORSO, strict=True)})
                self._posture_ref = torso
        for name in active:
            self._points[name].servo(self, getattr(targets, name))
        if targets.waist is None:  # BODY held at the reference
            hold = (float(base_pos_world[2]), *np.asarray(base_rpy_rad, dtype=float).tolist())
            if hold != self._hold:
                self.body_z_task.target_world = np.array((0.0, 0.0, hold[0]))
                self.body_R_task.R_world_frame = np.array(rpy_to_rows(*hold[1:]))
                self._hold = hold
        else:
            self._hold = None
        self._update_com_polygon()
        # step bounds on the free joints: velocity limit, and braking toward the position limits
        self._update_bounds(q, step)
        ok = True
        try:
            for it in range(p.iterations):
                if it:
                    self._forward_kinematics()
                self.solver.solve(True)
        except RuntimeError:  # placo's QPError: keep the previous tick's posture
            ok = False
            robot.state.q = q
        self._forward_kinematics()
        q_prev, self.q = q, robot.state.q.copy()  # the getter is a view on placo's state
        points = self._results(targets, q_prev, step, ok)
        com = self._com_now()
        x, y, z = self.q[:3].tolist()
        return OperationIKResult(
            q_rad=read_only(self.q[self.idx_q]), base_pos_world=read_only(np.array((x, y, z))),
            base_rpy_rad=read_only(np.array(quat_xyzw_to_rpy(*self.q[3:7].tolist()))), points=MappingProxyType(points),
            active=True, ok=ok, com_world=read_only(np.array(com)), com_margin_m=self._polygon.margin(com[0], com[1]))

    def _solve_upper_body(self, targets, q, q_ref, seeding, base_pos_world, base_rpy_rad) -> OperationIKResult:
        """The rest of solve() with the base and legs fixed: the points, the torso posture, the COM guard."""
        p, robot = self.params, self.robot
        lower, upper = self._lower, self._upper
        step = p.joint_velocity_limit_rad_s * p.dt_s
        self._base_key = self._base_key_of(base_pos_world, base_rpy_rad)
        if seeding:  # the guard around the COM as it is at activation, in the BODY frame
            x, y, _ = self._com_in_base()
            self._polygon = _GuardBox(x, y, p.com_guard_m)
            if self._com_polygon is not None:
                self.solver.remove_constraint(self._com_polygon)
                self._com_polygon = None
        self._seeded = True
        if self._posture is not None:  # torso posture toward the reference
            torso = q_ref[_TORSO_SLICE]
            if torso != self._posture_ref:
                self._posture.set_joints({n: min(upper[i], max(lower[i], q_ref[i]))
                                          for n, i in zip(_TORSO_NAMES, _TORSO, strict=True)})
                self._posture_ref = torso
        for name in self._active:
            self._points[name].servo(self, getattr(targets, name))
        # the guard: a hard constraint on c + dc/dt * T (com_guard_braking_time_s), the box in the world (the
        # guard is in the BODY frame), rebuilt when the base moves
        base = self._base_key
        if self._com_polygon is None or self._guard_base != base:
            R = rpy_to_rows(*base[3:])
            world = [np.array((base[0] + R[0][0] * v[0] + R[0][1] * v[1], base[1] + R[1][0] * v[0] + R[1][1] * v[1]))
                     for v in self._polygon.clockwise]
            if self._com_polygon is None:
                self.solver.dt = p.dt_s
                self._com_polygon = self.solver.add_com_polygon_constraint(world, 0.0)
                self._com_polygon.dcm = True
                self._com_polygon.omega = 1.0 / p.com_guard_braking_time_s
                self._configure_com_polygon(True)
            else:
                self._com_polygon.polygon = world
            self._guard_base = base
        self._update_bounds(q, step)
        ok = True
        try:
            for it in range(p.iterations):
                if it:
                    self._forward_kinematics()
                self.solver.solve(True)
        except RuntimeError:  # placo's QPError: keep the previous tick's posture
            ok = False
            robot.state.q = q
        self._forward_kinematics()
        q_prev, self.q = q, robot.state.q.copy()
        points = self._results(targets, q_prev, step, ok)
        com = self._com_now()
        cx, cy, _ = self._com_in_base()
        base = self._base_arrays
        if base[0] != self._base_key:  # the base arrays of the result, rebuilt when the base moves
            base = self._base_arrays = (self._base_key, read_only(np.array(self._base_key[:3])),
                                        read_only(np.array(self._base_key[3:])))
        return OperationIKResult(
            q_rad=read_only(self.q[self.idx_q]), base_pos_world=base[1], base_rpy_rad=base[2],
            points=MappingProxyType(points), active=True, ok=ok, com_world=read_only(np.array(com)),
            com_margin_m=self._polygon.margin(cx, cy))

    def _base_key_of(self, base_pos_world, base_rpy_rad) -> tuple[float, ...]:
        """The base pose as 6 floats; the last one again for the same two read-only arrays (the caller's
        constants, e.g. the upper-body caller's BODY frame origin)."""
        last = self._base_arg
        if base_pos_world is last[0] and base_rpy_rad is last[1]:
            return last[2]
        key = (*np.asarray(base_pos_world, dtype=float).tolist(), *np.asarray(base_rpy_rad, dtype=float).tolist())
        frozen = all(isinstance(a, np.ndarray) and not a.flags.writeable and a.base is None  # (no writeable base)
                     for a in (base_pos_world, base_rpy_rad))
        self._base_arg = (base_pos_world, base_rpy_rad, key) if frozen else (None, None, None)
        return key

    def _update_bounds(self, q: np.ndarray, step: float) -> None:
        """The step bounds' b for this tick: b = min((1 - k) Q + K, Q + step), Q = [q; -q] on the free joints
        ((1 - k) and step as arrays: a float scalar costs a numpy operation as much as the operation)."""
        if self._bound_step[0] != step:
            self._bound_step = (step, np.full(len(self._bound_q), step))
        qi = q[self._bound_q]
        b = qi * self._bound_sign_k  # (1 - k) Q
        b += self._bound_K
        Q = qi * self._bound_sign
        Q += self._bound_step[1]
        np.minimum(b, Q, out=b)
        self._bounds.b = b

    def _com_in_base(self) -> tuple[float, float, float]:
        """The COM in the BODY frame [m] (upper-body mode: the frame of the COM guard)."""
        base = self._base_key
        if self._base_rows[0] != base:
            self._base_rows = (base, rpy_to_rows(*base[3:]))
        return _tmulv(self._base_rows[1], _sub(self._com_now(), base[:3]))

    def _set_feet(self, feet: FeetPoses) -> None:
        last = self._feet_poses._keys if self._feet_poses is not None else (None, None)
        for (pos_task, ori_task), pos, R, key, key_last in zip(
                self._foot_tasks, (feet.p_rsole_world, feet.p_lsole_world), (feet.R_rsole_world, feet.R_lsole_world),
                feet._keys, last, strict=True):
            if key != key_last:  # only a sole that moved
                pos_task.target_world = pos
                ori_task.R_world_frame = R
        soles = tuple((pose, rect) for c, pose, rect in zip(feet.contact, feet._planar,
                                                            (HRP2_RIGHT_SOLE, HRP2_LEFT_SOLE), strict=True) if c)
        key = tuple(pose for pose, _ in soles), feet.contact
        if key != self._polygon_key:
            # the COM target 5 mm deeper than the margin: the constraint guards, it is not active all along
            self._polygon = _Polygon(soles, self.params.com_margin_m + _COM_TARGET_INSET_M)
            self._polygon_key = key
            self._set_com_target()
            if self._com_polygon is not None:
                self._com_polygon.polygon = self._polygon.clockwise
        self._feet_poses = feet

    def _set_com_target(self) -> None:
        """The COM x-y target: the COM at activation, or the nearest point inside the margin if it is not."""
        x, y = self._polygon.nearest_safe(*self._com_ref)
        self._com.target_world = np.array((x, y, 0.0))

    def _update_com_polygon(self) -> None:
        """The support-polygon constraint only while the COM is within 1 cm of the margin (it cannot get
        across in one tick); hard while inside the margin, soft (always feasible) while outside it."""
        p = self.params
        com = self._com_now()
        margin = self._polygon.margin(com[0], com[1])
        if margin > p.com_margin_m + 0.01:
            if self._com_polygon is not None:
                self.solver.remove_constraint(self._com_polygon)
                self._com_polygon = None
            return
        hard = margin >= p.com_margin_m - 1e-4
        if self._com_polygon is None:
            self._com_polygon = self.solver.add_com_polygon_constraint(self._polygon.clockwise, p.com_margin_m)
            self._configure_com_polygon(hard)
        elif hard != self._com_polygon_hard:
            self._configure_com_polygon(hard)

    def _results(self, targets, q_prev, step, ok) -> dict[str, PointResult]:
        p = self.params
        out: dict[str, PointResult] = {}
        lists = None
        for name in self._active:
            point = self._points[name]
            T, error_m, error_rad, scale = point.result(self, getattr(targets, name))
            limited = None
            if not ok:
                scale, limited = 0.0, SOLVER
            elif scale < p.limited_scale:
                lists = lists or (q_prev.tolist(), self.q.tolist())
                limited = self._limit_reason(point, *lists, step)
            out[name] = PointResult(T_world=read_only(T), error_m=error_m, error_rad=error_rad, scale=scale,
                                    limited=limited)
        return out

    def _limit_reason(self, point: _Point, q_prev: list, q_new: list, step: float) -> str:
        """JOINT_LIMIT if a joint of the point's own limb is braking at (or sits at) its position limit,
        VELOCITY if a joint of its chain runs at the velocity limit, else REACH. A joint is at a bound when
        its step came within 2 % (1e-7 rad at least) of it; which term of the bound was the smaller says
        which limit it is."""
        k = self._bound_k
        rows = point.bound_rows
        if rows is None:  # (placo index, upper, lower, in the limb) per chain joint, once
            rows = point.bound_rows = tuple((self._idx_q_list[i], self._upper[i], self._lower[i], i in point.limb_set)
                                            for i in point.chain_list)
        velocity = False
        for j, hi, lo, in_limb in rows:  # (conditionals, not min/max calls: this runs per joint)
            q0 = q_prev[j]
            dq = q_new[j] - q0
            up, down = k * (hi - q0), k * (q0 - lo)  # allowed steps
            if up > step:
                up = step
            if down > step:
                down = step
            tol = 0.02 * (up if up >= 0.0 else -up)
            if dq >= up - (tol if tol > 1e-7 else 1e-7):
                braking = up < step
            else:
                tol = 0.02 * (down if down >= 0.0 else -down)
                if -dq >= down - (tol if tol > 1e-7 else 1e-7):
                    braking = down < step
                else:
                    continue
            if braking and in_limb:
                return JOINT_LIMIT
            velocity = velocity or not braking
        return VELOCITY if velocity else REACH
