"""Recognitions off the control thread and out of the robot's process: the head-pose estimate and the model fit
run in the camera's process, on the image where it was rendered (a capture with an analysis); only the small
result comes back, and it enters the behaviour at a tick boundary."""

# Timing: a result is taken at the first tick boundary at least RECOGNITION_DELAY_S of control time after the
# capture at which it is ready (Capture.ready). When the loop runs as fast as possible (`--speed max`, or a test
# stepping it), that boundary waits for the result, so the result always arrives exactly RECOGNITION_DELAY_S
# after the capture and a seeded run is the same every time; paced, it is never waited for (a late result
# enters at a later boundary, which a recorded session keeps), so no tick is delayed.

from __future__ import annotations

from typing import Any

import numpy as np

from behaviors.base import Commands
from behaviors.perception.head_pose import T_world_camera_estimate
from behaviors.perception.locate import Recognition, locate_can, locate_trash_box
from behaviors.perception.locate_fridge import locate_fridge_handle
from behaviors.perception.locate_unknown import locate_unknown
from controller.core.types import OdometryEstimate
from controller.kinematics.model import RobotKinematics

#: Simulated time from a capture to its result [s]: the rendering and the fit take 0.1-0.2 s of wall time on
#: this 2-core machine (bench --scenario recognition), so paced at real time the result is nearly always ready.
RECOGNITION_DELAY_S = 0.3
LOCATORS = {"can": locate_can, "trash_box": locate_trash_box, "fridge_handle": locate_fridge_handle,
            "trash": locate_unknown}

_kin: RobotKinematics | None = None  # the analysing process's own model (the controller's belongs to the loop)


def prepare() -> None:
    """What recognise_image needs, loaded in the analysing process before its first image (the robot's model:
    ~0.1-0.3 s), so that the first recognition after a start or a scene change takes no longer than the others."""
    global _kin
    if _kin is None:
        _kin = RobotKinematics()


def recognise_image(frames, camera: str, time_s: float, q_meas_rad: np.ndarray, base_rpy_est_rad: np.ndarray,
                    odometry: OdometryEstimate, object_name: str) -> tuple[Recognition | None, Any]:
    """The analysis of a capture (Commands.capture's `analyse`): the robot's own estimate of the camera's pose
    from what it knew at the capture, and the object's model fitted to the image. (Recognition or None, the
    camera's intrinsics)."""
    prepare()
    image = frames[camera]
    T_world_camera = T_world_camera_estimate(_kin, q_meas_rad, base_rpy_est_rad, odometry, camera)
    locate = LOCATORS[object_name]
    return locate(image.rgb, image.depth_m, image.intrinsics, T_world_camera, time_s=time_s), image.intrinsics


class PendingRecognition:
    """One recognition under way: `poll(elapsed_s)` at each tick boundary gives None until the result is due,
    then (Recognition or None when nothing was found, the camera's intrinsics)."""

    def __init__(self, commands: Commands, camera: str, object_name: str) -> None:
        if object_name not in LOCATORS:
            raise ValueError(f"unknown object {object_name!r}; valid: {sorted(LOCATORS)}")
        self.object_name = object_name
        self.capture = commands.capture(camera, analyse=(recognise_image, (object_name,)))
        self.future = self.capture.frames

    def poll(self, elapsed_s: float) -> tuple[Recognition | None, Any] | None:
        if elapsed_s < RECOGNITION_DELAY_S - 1e-9:
            return None
        if not self.capture.ready():
            return None
        return self.future.result()

    def cancel(self) -> None:
        self.future.cancel()


def recognition_dict(r: Recognition, intrinsics) -> dict[str, Any]:
    """A recognition as published (JSON): object, world position [m], yaw [deg], 1-sigma per axis [m] and the
    covariance [m^2] from the image evidence, the image region [px], whether it touches the image border."""
    u0, v0, u1, v1 = r.bbox_px
    at_border = u0 <= 0 or v0 <= 0 or u1 >= intrinsics.width - 1 or v1 >= intrinsics.height - 1
    return {"object": r.object_name, "position_m": [round(float(v), 5) for v in r.position_world_m],
            "yaw_deg": round(float(np.degrees(r.yaw_rad)), 3),
            "sigma_m": [round(float(v), 5) for v in np.sqrt(np.diag(r.covariance_m2))],
            "covariance_m2": [[float(v) for v in row] for row in r.covariance_m2],
            "bbox_px": list(r.bbox_px), "n_pixels": int(r.n_pixels), "at_border": bool(at_border),
            "time_s": round(float(r.time_s), 4)}
