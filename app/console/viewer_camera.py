"""The 3D view's camera kept on the robot: each client's orbit camera moved by the followed body's horizontal
travel, so the operator's own orbit, zoom and height stay as they set them."""

from __future__ import annotations

import math

import numpy as np

FOLLOWED_BODY = "BODY"  # the body the 3D view's camera follows
FOLLOW_STEP_M = 0.002  # [m] the camera is moved once the body has gone this far (not at every sway)


class CameraFollower:
    """Keeps each client's orbit camera on the robot: on first sight (or when following starts) the camera is
    moved so that it looks at the followed body, then it is moved by the body's horizontal travel, so the
    operator's own orbit, zoom and height stay as they set them. `cameras` are viser CameraHandles (or anything
    with `position` and `look_at` in the world [m]; a camera the client has not reported yet is skipped)."""

    def __init__(self, step_m: float = FOLLOW_STEP_M) -> None:
        self.step_m = float(step_m)
        self._anchor_xy: dict[int, np.ndarray] = {}  # client id -> body x, y [m] the camera was last put on

    def restart(self) -> None:
        """Following (re)starts: each camera is put on the body again at the next update."""
        self._anchor_xy.clear()

    def update(self, cameras: dict, body_xy_m, atomic=None) -> int:
        """Move the cameras for the body at `body_xy_m` (world x, y [m]); how many moved. `atomic(client id)`, when
        given, is a context in which one camera's position and look-at change together."""
        body = np.asarray(body_xy_m, dtype=float)[:2]
        for gone in set(self._anchor_xy) - set(cameras):
            del self._anchor_xy[gone]
        moved = 0
        for cid, cam in cameras.items():
            try:
                look_at = np.asarray(cam.look_at, dtype=float)
                position = np.asarray(cam.position, dtype=float)
            except AssertionError:  # viser: the client has not reported its camera yet
                continue
            anchor = self._anchor_xy.get(cid)
            shift = body - (look_at[:2] if anchor is None else anchor)
            if anchor is not None and math.hypot(*shift) < self.step_m:
                continue
            if atomic is None:
                cam.position = position + (shift[0], shift[1], 0.0)  # viser moves the look-at point with it
            else:
                with atomic(cid):
                    cam.position = position + (shift[0], shift[1], 0.0)
            self._anchor_xy[cid] = body.copy()
            moved += 1
        return moved
