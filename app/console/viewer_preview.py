"""The preview's ghost in the 3D view: a behaviour's planned footsteps and hand paths (behaviors.preview, through
POST /api/behaviors/{name}/preview) drawn before it runs, in the world of leg odometry like the balance markers;
built once, then only moved, shown or hidden."""

from __future__ import annotations

import numpy as np

from app.console.viewer_markers import footstep_rectangles

MAX_GHOST_STEPS = 48  # planned footsteps drawn (fixed buffer)
MAX_GHOST_SEGMENTS = 160  # hand path segments drawn
GHOST_FOOT_RGB = (255, 120, 220)
GHOST_PATH_RGB = (255, 60, 160)
GHOST_Z_M = 0.004  # [m] above the floor, over the planned footsteps of the walk itself


def _fixed(segments: np.ndarray, n: int) -> np.ndarray:
    """Exactly n segments (the extra ones repeat the last, drawn over it); a zero one when there is none."""
    segments = np.asarray(segments, dtype=np.float32).reshape(-1, 2, 3)[:n]
    if len(segments) == 0:
        segments = np.zeros((1, 2, 3), dtype=np.float32)
    return np.concatenate([segments, np.repeat(segments[-1:], n - len(segments), axis=0)])


def ghost_segments(preview: dict) -> tuple[np.ndarray, np.ndarray]:
    """(footstep outlines, hand path segments) of a preview document, each (k, 2, 3) in the world [m]."""
    steps = [{"leg": "rleg" if s["side"] == "right" else "lleg", "pos": (s["x_m"], s["y_m"], GHOST_Z_M),
              "yaw": s["yaw_rad"]} for s in preview.get("footsteps", ())]
    feet = footstep_rectangles(steps, GHOST_Z_M) if steps else np.zeros((0, 2, 3))
    paths = [np.stack([p[:-1], p[1:]], axis=1) for p in (np.asarray(h["points_m"], dtype=float)
                                                          for h in preview.get("hand_paths", ())) if len(p) > 1]
    return feet, (np.concatenate(paths) if paths else np.zeros((0, 2, 3)))


class PreviewGhost:
    """The ghost's two line sets; `update(version, preview)` redraws when the version changes."""

    def __init__(self, scene) -> None:
        zero = np.zeros((1, 2, 3), dtype=np.float32)
        self.feet = scene.add_line_segments("/preview/footsteps", _fixed(zero, 4 * MAX_GHOST_STEPS), GHOST_FOOT_RGB,
                                            thickness=0.015, visible=False)
        self.paths = scene.add_line_segments("/preview/hand_paths", _fixed(zero, MAX_GHOST_SEGMENTS), GHOST_PATH_RGB,
                                             thickness=0.015, visible=False)
        self.version = 0
        self.shown = False

    def update(self, version: int, preview: dict | None) -> None:
        if version == self.version:
            return
        self.version = version
        feet, paths = ghost_segments(preview) if preview else (np.zeros((0, 2, 3)), np.zeros((0, 2, 3)))
        if len(feet):
            self.feet.points = _fixed(feet, 4 * MAX_GHOST_STEPS)
        if len(paths):
            self.paths.points = _fixed(paths, MAX_GHOST_SEGMENTS)
        self.feet.visible = bool(len(feet))
        self.paths.visible = bool(len(paths))
        self.shown = bool(len(feet) or len(paths))
