"""The robot's own estimate of a head camera's pose: encoders, the KalmanFilter attitude, the gait plan's odometry."""

# Nothing here reads the simulator. BODY's attitude is the KalmanFilter's (roll and pitch from gyro and
# accelerometer, yaw integrated from the gyro); BODY's position is the one the controller's state estimator
# anchors to the planned soles (the support foot does not slip: the gait plan's odometry), recovered from the
# snapshot's COG as cog_world - R(rpy) com_BODY(q). The head link follows from the encoders (forward
# kinematics of the controller's model), the camera from its mounting on the head (the robot's calibration,
# robot.generate.CAMERAS). Errors of any of these pass straight into T_world_camera and so into perception.

from __future__ import annotations

import numpy as np

from controller.kinematics.model import RobotKinematics
from robot.generate import CAMERAS

#: The link the head cameras are mounted on.
HEAD_LINK = "HEAD_LINK1"
#: Optical axes (x right, y down, z forward) in HEAD_LINK1: the cameras look along the head's +x, with the
#: image's right along -y and its down along -z (robot.generate.mjcf_cameras: xyaxes "0 -1 0 0 0 1").
R_HEAD_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def T_head_camera(camera: str) -> np.ndarray:
    """The camera's optical frame in HEAD_LINK1 (4, 4): its mounting, from the robot's calibration."""
    if camera not in CAMERAS:
        raise ValueError(f"unknown camera {camera!r}; valid cameras: {', '.join(CAMERAS)}")
    T = np.eye(4)
    T[:3, :3] = R_HEAD_OPTICAL
    T[:3, 3] = CAMERAS[camera][0]
    return T


def _checked(q_rad, base_rpy_rad, cog_world_m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    q = np.asarray(q_rad, dtype=float)
    rpy = np.asarray(base_rpy_rad, dtype=float)
    cog = np.asarray(cog_world_m, dtype=float)
    if q.shape != (30,) or rpy.shape != (3,) or cog.shape != (3,):
        raise ValueError(f"q_rad (30,), base_rpy_rad (3,) and cog_world_m (3,) expected, got {q.shape}, "
                         f"{rpy.shape}, {cog.shape}")
    return q, rpy, cog


def T_world_body_estimate(kin: RobotKinematics, q_rad, base_rpy_rad, cog_world_m) -> np.ndarray:
    """BODY in the world (4, 4) as the robot estimates it; leaves `kin` at that configuration.

    q_rad (30,) encoders, JOINT_NAMES order; base_rpy_rad (3,) the KalmanFilter's BODY attitude; cog_world_m (3,)
    the controller's estimated COG (encoders + attitude, anchored at the planned soles) [m]."""
    q, rpy, cog = _checked(q_rad, base_rpy_rad, cog_world_m)
    kin.update_rpy(np.zeros(3), rpy, q)  # BODY at the origin, world axes: the COG offset from BODY
    base_pos_world = cog - kin.com_world()
    kin.update_rpy(base_pos_world, rpy, q)
    T = np.eye(4)
    T[:3, :3] = kin.frame_pose("BODY")[1]
    T[:3, 3] = base_pos_world
    return T


def T_world_camera_estimate(kin: RobotKinematics, q_rad, base_rpy_rad, cog_world_m, camera: str) -> np.ndarray:
    """The camera's optical frame in the world (4, 4) as the robot estimates it (arguments as
    T_world_body_estimate's)."""
    T_head_cam = T_head_camera(camera)
    T_world_body_estimate(kin, q_rad, base_rpy_rad, cog_world_m)
    p_head, R_head = kin.frame_pose(HEAD_LINK)
    T_world_head = np.eye(4)
    T_world_head[:3, :3] = R_head
    T_world_head[:3, 3] = p_head
    return T_world_head @ T_head_cam


def T_world_camera_from_snapshot(kin: RobotKinematics, snapshot, camera: str) -> np.ndarray:
    """T_world_camera_estimate from a controller Snapshot (q_meas_rad, base_rpy_est_rad, cog_world)."""
    return T_world_camera_estimate(kin, snapshot.q_meas_rad, snapshot.base_rpy_est_rad, snapshot.cog_world, camera)
