"""The operation IK's inputs and outputs: the points' targets and the soles' poses (validated once), and what each
point achieved."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.types import read_only
from controller.kinematics.rotations import rpy_to_rows

#: The operational points, in the order they are solved and reported.
POINTS: tuple[str, ...] = ("rhand", "lhand", "head", "waist")

#: Why a point did less than it was asked this tick (PointResult.limited).
REACH = "reach"  # out of the workspace, at a singularity, or held back by balance, the torso or another point
JOINT_LIMIT = "joint_limit"  # a joint of its own limb brakes against (or sits at) its position limit
VELOCITY = "velocity"  # a joint of its chain runs at the joint velocity limit
SOLVER = "solver"  # the QP failed; the previous posture is kept


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
        object.__setattr__(self, "rows", (tuple(p.tolist()), tuple(map(tuple, R.tolist()))))

    @classmethod
    def from_rows(cls, p_world: tuple[float, float, float], R_world: tuple) -> HandTarget:
        """trusted() from floats: a position 3-tuple and the rotation's 3 row tuples (kept as `rows`)."""
        t = object.__new__(cls)
        object.__setattr__(t, "p_world", read_only(np.array(p_world)))
        object.__setattr__(t, "R_world", read_only(np.array(R_world)))
        object.__setattr__(t, "rows", (p_world, R_world))
        return t

    @classmethod
    def trusted(cls, p_world: np.ndarray, R_world: np.ndarray) -> HandTarget:
        """A target from a pose the caller built as a rotation (e.g. one integrated every tick), unchecked:
        the checks of __init__ cost more than the rest of a tick's bookkeeping."""
        t = object.__new__(cls)
        object.__setattr__(t, "p_world", p_world)
        object.__setattr__(t, "R_world", R_world)
        object.__setattr__(t, "rows", (tuple(p_world.tolist()), tuple(map(tuple, R_world.tolist()))))
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
        object.__setattr__(self, "R_rows", rpy_to_rows(*rpy.tolist()))


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
        object.__setattr__(self, "planar_soles", planar)  # (x [m], y [m], yaw [rad]) of each sole
        object.__setattr__(self, "sole_keys", tuple((*p.tolist(), *R.ravel().tolist()) for p, R in soles))


class PointResult(NamedTuple):
    """What an operational point achieved this tick (a NamedTuple: several are built every tick).

    `scale` in [0, 1]: the part of this tick's requested step (servo target minus the pose before the
    solve; rotation weighted by scale_length_m) the point achieved along the requested direction; 1 when
    the request is under the deadband. A caller integrating velocity commands multiplies them by it (the
    point slows down and keeps its direction) and, whenever `limited` is set, clamps its target to the
    achieved pose `T_world`, so its target never runs away from the robot.
    """

    T_world: np.ndarray  # (4, 4) achieved frame pose (hands: rarm_end/larm_end, head: HEAD_LINK1, waist: BODY)
    error_m: float | None  # |target - achieved| position [m] (head: 0; waist: height); None: a lean solve
    error_rad: float | None  # rotation angle from achieved to target [rad] (head: between the gaze axes)
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


NO_POINTS: Mapping[str, PointResult] = MappingProxyType({})
