"""BODY in the feet frame F (where the AutoBalancer put it), and the points' targets and poses between F and
BODY (the frame the upper-body IK works in)."""

from __future__ import annotations

import math

import numpy as np

from controller.core.types import Reference
from controller.kinematics.model import RobotKinematics
from controller.kinematics.operation_targets import GazeTarget, HandTarget, OperationTargets
from controller.kinematics.rotations import rows_mul, rows_mulv, rows_tmul, rows_tmulv
from controller.operation.frame import PlanarFrame, sub3
from controller.operation.targets import GazeAngles, HandPose, feet_frame
from robot.names import JOINT_GROUPS

#: the model frame of each IK point (the head's is the gaze: its x axis)
POINT_FRAMES = {"rhand": "rarm_end", "lhand": "larm_end", "head": "HEAD_LINK1", "waist": "BODY"}
NECK_FRAME = "HEAD_LINK0"  # the gaze ray's origin
_LOOK_AT_DISTANCE_M = 100.0  # a gaze direction becomes a point this far along it (neck drift: < 0.03 deg)
_LEGS = np.array(JOINT_GROUPS["rleg"] + JOINT_GROUPS["lleg"])


class BodyInFeet:
    """F in the world and BODY in F: from the gait the AutoBalancer published last tick, or without one from
    the reference's own soles (their F cached while its base and legs do not move)."""

    __slots__ = ("_kin", "_key", "_frame")

    def __init__(self) -> None:
        self._kin = RobotKinematics()  # the upstream reference's own soles (F without a gait)
        self._key: tuple | None = None
        self._frame: PlanarFrame | None = None

    def of(self, ref: Reference, gait) -> tuple[PlanarFrame, np.ndarray, np.ndarray]:
        """(F in the world, BODY position (3,) [m] and rotation (3, 3) in F)."""
        F, p_body, R_body = self.of_rows(ref, gait)
        return F, np.array(p_body), np.array(R_body)

    def of_rows(self, ref: Reference, gait) -> tuple[PlanarFrame, tuple, tuple]:
        """of() with BODY's pose as floats: position (3 floats [m]) and rotation rows."""
        if gait is not None and gait.base_pos_world is not None:
            F = PlanarFrame(*feet_frame(*rest_soles(gait)))
            return F, *F.to_local_rpy_rows(gait.base_pos_world, gait.base_rpy_rad)
        F = self.reference_frame(ref)
        return F, *F.to_local_rpy_rows(ref.base_pos_world, ref.base_rpy_rad)

    def reference_frame(self, ref: Reference) -> PlanarFrame:
        """F of the upstream reference (its own soles)."""
        key = (*ref.base_pos_world.tolist(), *ref.base_rpy_rad.tolist(), *ref.q_rad[_LEGS].tolist())
        if key != self._key:
            kin = self._kin
            kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, ref.q_rad)
            (pr, Rr), (pl, Rl) = kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")
            self._frame = PlanarFrame(*feet_frame(pr, Rr, pl, Rl))
            self._key = key
        return self._frame


def rest_soles(gait) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The gait's soles (p, R right; p, R left) with a foot lifted by its operational point back at its rest
    place: F does not move with the foot (nor the hands held in F)."""
    pr, pl = gait.p_rsole_world, gait.p_lsole_world
    if gait.foot_lift is not None:
        foot, off = gait.foot_lift
        if foot == "rfoot":
            pr = pr - np.array(off)
        else:
            pl = pl - np.array(off)
    return pr, gait.R_rsole_world, pl, gait.R_lsole_world


def ik_targets(targets: dict, neck_feet_m: np.ndarray | None, p_body: list, R_body: list) -> OperationTargets:
    """The hand and gaze targets (in F, relative to the anchor) in the BODY frame, where the upper-body IK works;
    BODY's pose in F (relative to the anchor) as floats: position (3,) [m] and rotation rows; the gaze ray from
    the neck `neck_feet_m` (None: F's origin)."""
    kw = {}
    for point in ("rhand", "lhand"):
        pose = targets.get(point)
        if pose is not None:
            kw[point] = HandTarget.from_rows(rows_tmulv(R_body, sub3(pose.p_feet_m.tolist(), p_body)),
                                             rows_tmul(R_body, pose.R_feet_hand.tolist()))
    gaze = targets.get("head")
    if gaze is not None:
        nx, ny, nz = neck_feet_m.tolist() if neck_feet_m is not None else (0.0, 0.0, 0.0)
        cp = math.cos(gaze.pitch_rad)  # (GazeAngles.direction_feet on floats)
        dx, dy, dz = cp * math.cos(gaze.yaw_rad), cp * math.sin(gaze.yaw_rad), -math.sin(gaze.pitch_rad)
        look = (nx + _LOOK_AT_DISTANCE_M * dx, ny + _LOOK_AT_DISTANCE_M * dy, nz + _LOOK_AT_DISTANCE_M * dz)
        kw["head"] = GazeTarget.trusted_look_at(np.array(rows_tmulv(R_body, sub3(look, p_body))))
    return OperationTargets(**kw)


def achieved_pose(point: str, T_body_point: np.ndarray, p_body: list, R_body: list):
    """A point's achieved pose in F (relative to the anchor) from the IK's (4, 4) in BODY; BODY's pose as in
    ik_targets: a GazeAngles for the head, else a HandPose."""
    (a0, a1, a2, x), (a3, a4, a5, y), (a6, a7, a8, z), _ = T_body_point.tolist()
    if point == "head":  # the gaze: the x axis
        return GazeAngles.of_direction(rows_mulv(R_body, (a0, a3, a6)))
    px, py, pz = rows_mulv(R_body, (x, y, z))
    return HandPose.owned(np.array((p_body[0] + px, p_body[1] + py, p_body[2] + pz)),
                          np.array(rows_mul(R_body, ((a0, a1, a2), (a3, a4, a5), (a6, a7, a8)))))
