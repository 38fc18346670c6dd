"""The robot's own estimate of a head camera's pose: encoders, the KalmanFilter attitude, leg odometry."""

# Nothing here reads the simulator. BODY's roll and pitch are the KalmanFilter's (gyro and accelerometer); its
# place and heading in the world come from leg odometry (controller.balance.leg_odometry: the stance sole, placed
# in the world step by step through the encoders), with BODY placed from that sole by the encoders. The head
# link follows from the encoders (forward kinematics of the controller's model), the camera from its mounting on
# the head (the robot's calibration, robot.robot_model.CAMERAS). Errors of any of these pass straight into
# T_world_camera and so into perception. The controller's own frame (the gait plan's, which a walk's landing
# errors move off the world: 19 mm after 1.0 m) is not used: a behaviour that acts on a location takes it into
# the plan's frame through the odometry's world_from_control.

from __future__ import annotations

import numpy as np

from controller.core.types import OdometryEstimate
from controller.kinematics.model import RobotKinematics
from robot.generate import CAMERAS

#: The link the head cameras are mounted on.
HEAD_LINK = "HEAD_LINK1"
#: Optical axes (x right, y down, z forward) in HEAD_LINK1: the cameras look along the head's +x, with the
#: image's right along -y and its down along -z (robot.robot_model.mjcf_cameras: xyaxes "0 -1 0 0 0 1").
R_HEAD_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def T_head_camera(camera: str) -> np.ndarray:
    """The camera's optical frame in HEAD_LINK1 (4, 4): its mounting, from the robot's calibration."""
    if camera not in CAMERAS:
        raise ValueError(f"unknown camera {camera!r}; valid cameras: {', '.join(CAMERAS)}")
    T = np.eye(4)
    T[:3, :3] = R_HEAD_OPTICAL
    T[:3, 3] = CAMERAS[camera][0]
    return T


def _checked(q_rad, base_rpy_rad, odometry) -> tuple[np.ndarray, np.ndarray, OdometryEstimate]:
    q = np.asarray(q_rad, dtype=float)
    rpy = np.asarray(base_rpy_rad, dtype=float)
    if q.shape != (30,) or rpy.shape != (3,):
        raise ValueError(f"q_rad (30,) and base_rpy_rad (3,) expected, got {q.shape}, {rpy.shape}")
    if not isinstance(odometry, OdometryEstimate):
        raise ValueError(f"odometry must be the state estimator's OdometryEstimate (the snapshot's), got "
                         f"{type(odometry).__name__}")
    return q, rpy, odometry


def T_world_body_estimate(kin: RobotKinematics, q_rad, base_rpy_rad, odometry: OdometryEstimate) -> np.ndarray:
    """BODY in the world (4, 4) as the robot estimates it; leaves `kin` at that configuration.

    q_rad (30,) encoders, JOINT_NAMES order; base_rpy_rad (3,) the KalmanFilter's BODY attitude; odometry: the
    leg odometry of the same tick, which hangs BODY from the stance sole by these encoders and turns it about
    the vertical by its heading less the KalmanFilter's (world_from_control's yaw)."""
    q, rpy, odo = _checked(q_rad, base_rpy_rad, odometry)
    base_pos_world = np.array(odo.p_body_world_m)
    dyaw = odo.world_from_control[3]
    kin.update_rpy(base_pos_world, (rpy[0], rpy[1], rpy[2] + dyaw), q)  # Rz(dyaw) Rz(y) Ry(p) Rx(r)
    T = np.eye(4)
    T[:3, :3] = kin.frame_pose("BODY")[1]
    T[:3, 3] = base_pos_world
    return T


def T_world_camera_estimate(kin: RobotKinematics, q_rad, base_rpy_rad, odometry: OdometryEstimate,
                            camera: str) -> np.ndarray:
    """The camera's optical frame in the world (4, 4) as the robot estimates it (arguments as
    T_world_body_estimate's)."""
    T_head_cam = T_head_camera(camera)
    T_world_body_estimate(kin, q_rad, base_rpy_rad, odometry)
    p_head, R_head = kin.frame_pose(HEAD_LINK)
    T_world_head = np.eye(4)
    T_world_head[:3, :3] = R_head
    T_world_head[:3, 3] = p_head
    return T_world_head @ T_head_cam


def T_world_camera_from_snapshot(kin: RobotKinematics, snapshot, camera: str) -> np.ndarray:
    """T_world_camera_estimate from a controller Snapshot (q_meas_rad, base_rpy_est_rad, odometry)."""
    return T_world_camera_estimate(kin, snapshot.q_meas_rad, snapshot.base_rpy_est_rad, snapshot.odometry, camera)
