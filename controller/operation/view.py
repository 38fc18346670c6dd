"""What behaviours read of the operation layer between ticks: the OperationView of its last output, computed once
per tick from what that tick saw."""

from __future__ import annotations

from controller.core.errors import InvalidCommand
from controller.core.types import Reference, frozen_array
from controller.kinematics.model import RobotKinematics
from controller.operation.body_frame import POINT_FRAMES, BodyInFeet
from controller.operation.frame import sole_from_sole
from controller.operation.points import OperationView, PointPose
from controller.operation.targets import GazeAngles

_SOLES_APART = OperationView.__dataclass_fields__["lsole_from_rsole"].default  # (half-sitting, without a gait)


class LastTick:
    """What the layer's last tick saw and put out: control time [s], the AutoBalancer's gait port, walking, the
    motion stopped, the CollisionDetector's held pairs, the input and output references."""

    __slots__ = ("time_s", "gait", "walking", "stopped", "collision_pairs", "ref_in", "ref_out")

    def __init__(self) -> None:
        self.time_s = 0.0
        self.gait = None
        self.walking = False
        self.stopped = False
        self.collision_pairs: tuple[tuple[str, str], ...] = ()
        self.ref_in: Reference | None = None
        self.ref_out: Reference | None = None


class ViewOfTick:
    """The points as the last output reference puts them (FK of the controller's reference, placed in the world
    by the gait's feet frame), the gaze and waist height in F; one view per tick, shared by its readers."""

    __slots__ = ("_kin", "_frame_ids", "_cache")

    def __init__(self) -> None:
        self._kin = RobotKinematics()  # the output reference's FK (joints only, 4 frames)
        self._frame_ids = {point: self._kin.model.getFrameId(frame) for point, frame in POINT_FRAMES.items()}
        self._cache: tuple | None = None  # ((ref, gait, time, walking, stopped, pairs), the view of that tick)

    def of(self, last: LastTick, frames: BodyInFeet) -> OperationView:
        ref = last.ref_out or last.ref_in
        if ref is None:
            raise InvalidCommand("the operation layer has not ticked yet; no view before the first tick")
        gait = last.gait
        key = (ref, gait, last.time_s, last.walking, last.stopped, last.collision_pairs)
        cached = self._cache
        if cached is not None and cached[0][0] is ref and cached[0][1] is gait and cached[0][2:] == key[2:]:
            return cached[1]
        F_world, p_body, R_body = frames.of(ref, gait)
        kin = self._kin
        kin.update_joints(p_body, R_body, ref.q_rad)  # in F, BODY where the AutoBalancer has it
        points = {}
        for point, fid in self._frame_ids.items():
            (a0, a1, a2, x), (a3, a4, a5, y), (a6, a7, a8, z), _ = kin.frame_homogeneous(fid).tolist()
            R_feet = ((a0, a1, a2), (a3, a4, a5), (a6, a7, a8))
            p_w, R_w = F_world.to_world_rows((x, y, z), R_feet)
            points[point] = PointPose(p_world_m=frozen_array(p_w), R_world_point=frozen_array(R_w),
                                      p_feet_m=frozen_array((x, y, z)), R_feet_point=frozen_array(R_feet))
        if gait is not None:  # the soles as the AutoBalancer plans them (a lifted one where it lifted it)
            for point, p_w, R_w in (("rfoot", gait.p_rsole_world, gait.R_rsole_world),
                                    ("lfoot", gait.p_lsole_world, gait.R_lsole_world)):
                p_f, R_f = F_world.to_local(p_w, R_w)
                points[point] = PointPose(p_world_m=frozen_array(p_w), R_world_point=frozen_array(R_w),
                                          p_feet_m=frozen_array(p_f), R_feet_point=frozen_array(R_f))
        gaze = GazeAngles.of_direction(points["head"].R_feet_point[:, 0])
        soles = _SOLES_APART if gait is None else sole_from_sole(gait.p_rsole_world, gait.R_rsole_world,
                                                                 gait.p_lsole_world, gait.R_lsole_world)
        view = OperationView(time_s=last.time_s, feet_p_world_m=frozen_array(F_world.p), feet_yaw_rad=F_world.yaw,
                             points=points, gaze_rad=(gaze.pitch_rad, gaze.yaw_rad),
                             waist_height_m=float(points["waist"].p_feet_m[2]), walking=last.walking,
                             motion_stopped=last.stopped, collision_pairs=last.collision_pairs,
                             lsole_from_rsole=soles,
                             foot_lifted=None if gait is None or gait.foot_lift is None else gait.foot_lift[0])
        self._cache = (key, view)
        return view
