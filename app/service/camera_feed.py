"""The operator's view through the wide head camera ([OP] V-A's online camera view), drawn in the console
process from the state the robot publishes (the same board the snapshots come by: no channel into the
controller, and no rendering or encoding in the robot process, whose loop therefore never waits for either).

While a watcher's lease runs, the feed's thread takes each new publication (at most VIEW_RATE_HZ), has the
camera process (robot.camera.CameraProcess: MuJoCo's renderer holds the interpreter lock while it works, ~8 ms a
frame and ~0.5 s for its GL context, which here would hold up the HTTP server and an e-stop) draw the wide camera
from its qpos
and mocap poses, encodes the JPEG and draws nothing itself: the recognitions go beside the image as boxes the
page draws. A slow machine drops publications, it never queues them."""

from __future__ import annotations

import io
import logging
import math
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from behaviors.perception.geometry import project, transform
from behaviors.perception.models import CAN, TRASH_BOX
from robot.images import CameraIntrinsics

log = logging.getLogger(__name__)

VIEW_CAMERA = "wide"  # 93.6 x 70.8 deg (robot/robot_model.py CAMERAS)
VIEW_SIZE_PX = (320, 240)  # small: one rendering and encoding costs a few ms of the machine's time
VIEW_RATE_HZ = 15.0  # [Hz] of wall time, at most, while watched
DEFAULT_RATE_HZ = 10.0  # [Hz] unless a watcher asks for more
LEASE_S = 2.0  # [s] of wall time a watch lasts unless renewed
JPEG_QUALITY = 70
#: Half extents [m] of the box drawn around a recognised object (its model, centred on the estimate).
OBJECT_HALF_EXTENTS_M = {
    "can": (CAN.radius_m, CAN.radius_m, CAN.height_m / 2),
    "trash_box": (TRASH_BOX.lid_m[0] / 2, TRASH_BOX.lid_m[1] / 2, 0.05),
}
DEFAULT_HALF_EXTENTS_M = (0.05, 0.05, 0.05)
NEAR_M = 0.05  # [m] corners closer to the camera plane than this are not projected


@dataclass(frozen=True)
class CameraFrame:
    """One published view: the JPEG and what it shows."""

    camera: str
    seq: int  # increases with every frame of this robot process
    time_s: float  # control time of the state shown [s]
    width: int
    height: int
    jpeg: bytes
    requested_at_monotonic_s: float
    rendered_at_monotonic_s: float
    render_wall_s: float  # rendering, on the render thread [s]
    encode_wall_s: float  # JPEG and overlays [s]
    overlays: tuple = ()  # recognitions drawn over it: dicts (see overlay())
    source: tuple = ()  # (generation, seq) of the publication shown

    def meta(self) -> dict[str, Any]:
        """Everything but the image, as JSON."""
        return {"camera": self.camera, "seq": self.seq, "time_s": round(self.time_s, 4), "width": self.width,
                "height": self.height, "bytes": len(self.jpeg), "render_ms": round(1e3 * self.render_wall_s, 2),
                "encode_ms": round(1e3 * self.encode_wall_s, 2), "recognitions": list(self.overlays)}


def encode_jpeg(rgb: np.ndarray, quality: int = JPEG_QUALITY) -> bytes:
    """An (H, W, 3) uint8 image as JPEG bytes."""
    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgb)).save(out, format="JPEG", quality=int(quality))
    return out.getvalue()


def box_corners_world(position_m, yaw_rad: float, half_extents_m) -> np.ndarray:
    """(8, 3) corners of a box centred at `position_m` [m], yawed `yaw_rad` about world z."""
    hx, hy, hz = (float(v) for v in half_extents_m)
    local = np.array([[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return local @ R.T + np.asarray(position_m, dtype=float)


def image_box_px(T_world_camera, intrinsics: CameraIntrinsics, corners_world) -> list[float] | None:
    """The image rectangle [u0, v0, u1, v1] [px] around the projections of `corners_world`, clipped to the image;
    None when any corner is behind (or too near) the camera plane or the rectangle misses the image."""
    p = transform(np.linalg.inv(np.asarray(T_world_camera, dtype=float)), corners_world)
    if np.any(p[:, 2] < NEAR_M):
        return None
    uv = project(p, intrinsics)
    u0, v0 = uv.min(axis=0)
    u1, v1 = uv.max(axis=0)
    w, h = intrinsics.width - 1, intrinsics.height - 1
    if u1 < 0 or v1 < 0 or u0 > w or v0 > h:
        return None
    return [round(float(np.clip(u0, 0, w)), 1), round(float(np.clip(v0, 0, h)), 1),
            round(float(np.clip(u1, 0, w)), 1), round(float(np.clip(v1, 0, h)), 1)]


def overlay(name: str, recognition: Mapping[str, Any], T_world_camera, intrinsics: CameraIntrinsics) -> dict:
    """A recognition as drawn over the view: the published fields the page shows, and the image box of the
    object's model around its estimated position (null when it is out of view)."""
    position = recognition["position_m"]
    corners = box_corners_world(position, math.radians(float(recognition.get("yaw_deg", 0.0))),
                                OBJECT_HALF_EXTENTS_M.get(name, DEFAULT_HALF_EXTENTS_M))
    keep = ("object", "position_m", "sigma_m", "yaw_deg", "time_s", "status", "estimated_position_m", "bbox_px",
            "verdict_detail")
    return {"name": name, **{k: recognition[k] for k in keep if k in recognition},
            "box_px": image_box_px(T_world_camera, intrinsics, corners)}


class CameraFeed:
    """The watched view of one camera, drawn from the robot's published state. `watch()` starts or renews the
    lease; meanwhile the feed's thread renders each new publication (at most `rate_hz`) on the rig's render
    thread, encodes it and annotates it with the recognitions; `latest` is the newest frame."""

    def __init__(self, source: Callable[[], Any], camera: str = VIEW_CAMERA, size_px: tuple[int, int] = VIEW_SIZE_PX,
                 rate_hz: float = VIEW_RATE_HZ) -> None:
        """`source()`: the robot's latest app.service.host.Published (raises ServiceError while it has none)."""
        self.camera = camera
        self.size_px = (int(size_px[0]), int(size_px[1]))
        self.max_rate_hz = float(rate_hz)
        self._rates: dict[float, float] = {}  # rate a watcher asked for [Hz] -> until when (monotonic) [s]
        self._source = source
        self._until = 0.0
        self._rig = None
        self._rig_scene: str | None = None
        self.error: str | None = None  # why no frame can be rendered (no renderer), else None
        self._seq = 0
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._closed = False
        self._thread: threading.Thread | None = None
        self._kin = None  # the feed thread's own kinematics (overlays)
        self.latest: CameraFrame | None = None
        self.frames = 0

    def __repr__(self) -> str:
        return f"CameraFeed({self.camera!r}, {self.size_px[0]}x{self.size_px[1]} px, frames={self.frames})"

    def watch(self, seconds: float = LEASE_S, rate_hz: float = DEFAULT_RATE_HZ) -> None:
        """Someone watches for `seconds` more (wall time), `rate_hz` frames a second (at most max_rate_hz): the
        feed renders at the highest rate asked for by a watcher whose lease runs."""
        now = time.monotonic()
        until = now + float(seconds)
        self._until = max(self._until, until)
        rate = min(float(rate_hz), self.max_rate_hz)
        with self._lock:
            self._rates[rate] = max(self._rates.get(rate, 0.0), until)
            for r in [r for r, u in self._rates.items() if u <= now]:
                del self._rates[r]
        with self._lock:
            if self._closed:
                return
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="camera-feed", daemon=True)
                self._thread.start()
        self._wake.set()

    @property
    def watched(self) -> bool:
        return time.monotonic() < self._until

    @property
    def period_s(self) -> float:
        """[s] between two frames: the highest rate a watcher asked for."""
        now = time.monotonic()
        rates = [r for r, u in list(self._rates.items()) if u > now]
        return 1.0 / (max(rates) if rates else DEFAULT_RATE_HZ)

    def _run(self) -> None:
        due = time.monotonic()
        last_key = None
        while not self._closed:
            if not self.watched:
                self._wake.clear()
                self._wake.wait(0.5)
                due = time.monotonic()
                continue
            now = time.monotonic()
            if now < due:
                time.sleep(due - now)
            due = max(due + self.period_s, time.monotonic())
            try:
                pub = self._source()
            except Exception:  # noqa: BLE001 - the robot process is down or restarting: try again
                time.sleep(0.5)
                continue
            key = (pub.generation, pub.seq)
            if key == last_key or pub.truth.qpos is None:
                continue
            last_key = key
            try:
                self._frame(pub)
            except Exception as exc:  # noqa: BLE001 - the view says why; nothing else is affected
                if self.error is None:
                    log.exception("camera frame failed")
                self.error = f"{type(exc).__name__}: {exc}"
                time.sleep(0.5)

    def _rig_for(self, scene: str):
        if self._rig is None or self._rig_scene != scene:
            from robot.camera import CameraProcess

            if self._rig is not None:
                self._rig.close()
                self._rig = None
            # no model in this process (loading one takes the lock ~0.1 s): the child says the sizes
            self._rig = CameraProcess(scene, None, cameras=(self.camera,), width=self.size_px[0],
                                      height=self.size_px[1], depth_cameras=())
            self._rig_scene = scene
        return self._rig

    def _frame(self, pub) -> CameraFrame:
        truth, snap = pub.truth, pub.snapshot
        rig = self._rig_for(pub.scene)
        requested = time.monotonic()
        frames = rig.render(truth.qpos, truth.time_s, truth.mocap_pos, truth.mocap_quat)
        rendered = time.monotonic()
        start = time.perf_counter()
        image = frames[self.camera]
        jpeg = encode_jpeg(image.rgb)
        recognitions = getattr(pub, "recognitions", None) or {}
        overlays = self._overlays(recognitions, snap, image.intrinsics) if recognitions else ()
        self._seq += 1
        frame = CameraFrame(self.camera, self._seq, float(snap.time_s), image.intrinsics.width,
                            image.intrinsics.height, jpeg, requested, rendered, frames.render_wall_s,
                            time.perf_counter() - start, overlays, (pub.generation, pub.seq))
        self.latest = frame
        self.frames += 1
        self.error = None
        return frame

    def _overlays(self, recognitions, snap, intrinsics) -> tuple:
        """Each recognition's box in this view, from the robot's own estimate of the camera's pose (encoders,
        KalmanFilter attitude, estimated COG of the snapshot)."""
        from behaviors.perception.head_pose import T_world_camera_from_snapshot

        if self._kin is None:
            from controller.kinematics.model import RobotKinematics

            self._kin = RobotKinematics()
        T_world_camera = T_world_camera_from_snapshot(self._kin, snap, self.camera)
        out = []
        for name, rec in sorted(recognitions.items()):
            try:
                out.append(overlay(name, rec, T_world_camera, intrinsics))
            except (KeyError, TypeError, ValueError) as exc:
                log.debug("recognition %s not drawn: %s", name, exc)
        return tuple(out)

    def close(self) -> None:
        with self._lock:
            self._closed = True
            thread = self._thread
        self._wake.set()
        if thread is not None:
            thread.join(timeout=5.0)
        if self._rig is not None:
            self._rig.close()
            self._rig = None
