"""What the head cameras hand perception: images, depth and pinhole intrinsics (plain numpy, no simulator)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class CameraIntrinsics:
    """Pinhole model in pixels, OpenCV conventions: pixel (u, v) = (column, row) with pixel centres at integers,
    camera (optical) frame x right, y down, z along the view; u = fx x / z + cx, v = fy y / z + cy."""

    width: int
    height: int
    fx: float  # [px]
    fy: float  # [px]
    cx: float  # [px]
    cy: float  # [px]

    def __post_init__(self) -> None:
        if self.width <= 0 or self.height <= 0:
            raise ValueError(f"width and height must be positive pixel counts, got {self.width} x {self.height}")
        if not (self.fx > 0 and self.fy > 0):
            raise ValueError(f"fx and fy must be > 0 [px], got {self.fx}, {self.fy}")

    @property
    def hfov_deg(self) -> float:
        """Horizontal field of view [deg] (edge to edge of the image)."""
        return float(np.degrees(2 * np.arctan2(self.width / 2, self.fx)))

    @property
    def vfov_deg(self) -> float:
        return float(np.degrees(2 * np.arctan2(self.height / 2, self.fy)))

    def matrix(self) -> np.ndarray:
        """K (3, 3)."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])


@dataclass(frozen=True, slots=True)
class CameraImage:
    """One camera's picture at one instant.

    `depth_m` is the metric depth along the optical axis (z, not the ray length) per pixel, float32 [m],
    +inf where nothing was hit; None for a camera without depth. No pose: the robot places the image with its
    own estimate of the camera pose (the simulator's is in Frames, for tests).
    """

    camera: str
    rgb: np.ndarray  # (H, W, 3) uint8
    depth_m: np.ndarray | None  # (H, W) float32 [m]
    intrinsics: CameraIntrinsics


@dataclass(frozen=True, slots=True)
class Frames:
    """The images of one request: camera name -> CameraImage, all of the same simulated instant.

    `T_world_camera_true` is the simulator's pose of each camera (optical frame, (4, 4)), beside the images
    and not in them: ground truth for tests measuring an error, never an input of perception."""

    time_s: float  # simulated time of the state they show [s]
    images: dict[str, CameraImage]
    render_wall_s: float  # wall time spent rendering them [s]
    T_world_camera_true: dict[str, np.ndarray]  # camera name -> (4, 4), tests only

    def __getitem__(self, camera: str) -> CameraImage:
        try:
            return self.images[camera]
        except KeyError:
            raise KeyError(f"no image from {camera!r}; rendered: {', '.join(self.images)}") from None
