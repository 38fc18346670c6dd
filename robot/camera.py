"""The simulated head cameras: one offscreen MuJoCo renderer on one thread, fed copies of the plant state."""

from __future__ import annotations

import copy
import logging
import math
import os
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from robot.images import CameraImage, CameraIntrinsics, Frames
from robot.plant import scene_path

#: The head cameras [OP sec. V] (robot/robot_model.py CAMERAS): narrow stereo pair and the wide teleoperation camera.
HEAD_CAMERAS: tuple[str, ...] = ("narrow_left", "narrow_right", "wide")
#: Depth comes with the left narrow camera only: a simulated stereo sensor (narrow pair, 0.144 m baseline)
#: whose depth map is registered to the left image. The wide camera has no stereo partner.
DEPTH_CAMERAS: tuple[str, ...] = ("narrow_left",)

#: MuJoCo camera frame (x right, y up, looking along -z) -> optical frame (x right, y down, z forward).
R_MUJOCO_OPTICAL = np.diag([1.0, -1.0, -1.0])
#: Depth at or beyond this fraction of the far clipping plane means nothing was hit.
FAR_FRACTION = 0.999


def camera_intrinsics(model: mujoco.MjModel, camera: str, width: int, height: int) -> CameraIntrinsics:
    """Pinhole intrinsics of a model camera rendered at width x height [px].

    A camera with `sensorsize` (the head cameras) has its fields of view from focal length and sensor size,
    stretched to the image: fx = f / sensor_x * width, fy = f / sensor_y * height. Otherwise MuJoCo's `fovy`
    gives fy = height / (2 tan(fovy / 2)) and square pixels (fx = fy). The principal point is the image centre.
    """
    cam = model.camera(camera).id
    sensor = model.cam_sensorsize[cam]
    if sensor[0] > 0 and sensor[1] > 0:
        f_x, f_y = model.cam_intrinsic[cam][:2]
        fx, fy = f_x / sensor[0] * width, f_y / sensor[1] * height
    else:
        fy = height / (2 * math.tan(math.radians(model.cam_fovy[cam]) / 2))
        fx = fy
    return CameraIntrinsics(width, height, float(fx), float(fy), (width - 1) / 2, (height - 1) / 2)


def stereo_baseline_m(model: mujoco.MjModel) -> float:
    """Distance between the narrow pair's optical centres [m] (0.144 m on HRP-2 No.10); 0 without the pair."""
    names = {model.camera(i).name for i in range(model.ncam)}
    if not {"narrow_left", "narrow_right"} <= names:
        return 0.0
    return float(np.linalg.norm(model.camera("narrow_left").pos - model.camera("narrow_right").pos))


def _copied_request(qpos, mocap_pos, mocap_quat, cameras, rendered: tuple[str, ...]):
    """A request's arrays copied (the caller may go on stepping) and its cameras (None: all the rig renders)."""
    q = np.array(qpos, dtype=float, copy=True)
    pos = None if mocap_pos is None else np.array(mocap_pos, dtype=float, copy=True).reshape(-1, 3)
    quat = None if mocap_quat is None else np.array(mocap_quat, dtype=float, copy=True).reshape(-1, 4)
    return q, pos, quat, rendered if cameras is None else tuple(cameras)


def _check_request(q, pos, quat, chosen, nq: int, nmocap: int, rendered: tuple[str, ...]) -> None:
    """ValueError naming what is wrong with a request for a model of nq positions and nmocap mocap bodies."""
    if q.shape != (nq,) or not np.all(np.isfinite(q)):
        raise ValueError(f"qpos must be {nq} finite numbers, got shape {q.shape}")
    for name, a in (("mocap_pos", pos), ("mocap_quat", quat)):
        if a is not None and a.shape[0] != nmocap:
            raise ValueError(f"{name} must have {nmocap} rows (one per mocap body), got {a.shape}")
    unknown = [c for c in chosen if c not in rendered]
    if unknown or not chosen:
        raise ValueError(f"cameras {unknown or chosen} not rendered by this rig; valid: {', '.join(rendered)}")


class CameraRig:
    """Renders the head cameras from snapshots of the plant state, on one dedicated render thread.

    EGL (and OSMesa) contexts belong to the thread that made them current, so the renderer is created, used
    and freed on the rig's single worker thread; callers only queue requests. Each request carries a copy of
    the state (qpos, and the mocap poses of fixed objects); the rig writes it into its own MjData, runs
    mj_forward and renders RGB for every camera and metric depth for DEPTH_CAMERAS. Shadows, reflections,
    the skybox and multisampling are off for speed. Set MUJOCO_GL=egl (or osmesa) before importing mujoco.

    Depth is the renderer's z-buffer, exact to float32: an ideal stereo sensor. `disparity_noise_px` > 0 adds
    the error of a real one: Gaussian noise on the disparity fx b / z of the narrow pair (baseline b), so the
    depth error grows as z^2 (about 2 mm at 1.2 m for 0.25 px). `seed` makes that noise repeatable.
    """

    def __init__(self, scene: str | Path | mujoco.MjModel = "default", cameras: Sequence[str] = HEAD_CAMERAS,
                 width: int = 640, height: int = 480, depth_cameras: Sequence[str] | None = None,
                 disparity_noise_px: float = 0.0, seed: int | None = None) -> None:
        if isinstance(scene, mujoco.MjModel):
            model = copy.copy(scene)  # the rig's own model: its visual settings change below
        else:
            model = mujoco.MjModel.from_xml_path(str(scene_path(scene)))
        known = [model.camera(i).name for i in range(model.ncam)]
        cameras = tuple(cameras)
        if depth_cameras is None:  # DEPTH_CAMERAS among those rendered
            depth_cameras = tuple(c for c in DEPTH_CAMERAS if c in cameras)
        for name in (*cameras, *depth_cameras):
            if name not in known:
                raise ValueError(f"unknown camera {name!r}; valid cameras: {', '.join(known)}")
        if not cameras:
            raise ValueError(f"cameras must name at least one camera; valid cameras: {', '.join(known)}")
        if not set(depth_cameras) <= set(cameras):
            raise ValueError(f"depth_cameras {tuple(depth_cameras)} must be among cameras {cameras}")
        if not (isinstance(width, int) and isinstance(height, int) and width > 0 and height > 0):
            raise ValueError(f"width and height must be positive integers [px], got {width!r} x {height!r}")
        if not (math.isfinite(disparity_noise_px) and disparity_noise_px >= 0):
            raise ValueError(f"disparity_noise_px must be >= 0 [px], got {disparity_noise_px!r}")
        model.vis.quality.offsamples = 0
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        self._model = model
        self._data = mujoco.MjData(model)
        self._cameras = cameras
        self._depth_cameras = tuple(depth_cameras)
        self._width, self._height = width, height
        self._intrinsics = {name: camera_intrinsics(model, name, width, height) for name in cameras}
        self._far_m = float(model.vis.map.zfar * model.stat.extent)
        self._baseline_m = stereo_baseline_m(model)
        self._disparity_noise_px = float(disparity_noise_px)
        self._rng = np.random.default_rng(seed)
        self._gl_thread_ids: set[int] = set()
        self._closed = False
        self._lock = threading.Lock()
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="camera-render")
        try:
            self._executor.submit(self._open).result()
        except Exception:
            self._executor.shutdown(wait=True)
            raise

    def __repr__(self) -> str:
        return (f"CameraRig(cameras={self._cameras}, depth={self._depth_cameras}, "
                f"{self._width}x{self._height} px, closed={self._closed})")

    # ------------------------------------------------------------------ render thread

    def _open(self) -> None:
        self._gl_thread_ids.add(threading.get_ident())
        try:
            self._renderer = mujoco.Renderer(self._model, self._height, self._width)
        except Exception as err:
            raise RuntimeError(f"cannot create an offscreen renderer ({err}); set MUJOCO_GL=egl or osmesa "
                               "before mujoco is imported") from err
        flags = self._renderer.scene.flags
        for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION,
                     mujoco.mjtRndFlag.mjRND_SKYBOX):
            flags[flag] = 0

    def _render(self, qpos: np.ndarray, time_s: float, mocap_pos, mocap_quat, cameras) -> Frames:
        self._gl_thread_ids.add(threading.get_ident())
        start = time.perf_counter()
        m, d = self._model, self._data
        d.qpos[:] = qpos
        d.qvel[:] = 0.0
        if mocap_pos is not None:
            d.mocap_pos[:] = mocap_pos
        if mocap_quat is not None:
            d.mocap_quat[:] = mocap_quat
        d.time = time_s
        mujoco.mj_forward(m, d)
        images, truth = {}, {}
        renderer = self._renderer
        for name in cameras:
            cam = m.camera(name).id
            renderer.update_scene(d, camera=cam)
            rgb = renderer.render()
            depth = None
            if name in self._depth_cameras:
                renderer.enable_depth_rendering()
                depth = renderer.render()
                renderer.disable_depth_rendering()
                depth[depth >= FAR_FRACTION * self._far_m] = np.inf
                if self._disparity_noise_px > 0:
                    self._add_stereo_noise(depth, self._intrinsics[name].fx)
                depth.flags.writeable = False
            rgb.flags.writeable = False
            T = np.eye(4)
            T[:3, :3] = d.cam_xmat[cam].reshape(3, 3) @ R_MUJOCO_OPTICAL
            T[:3, 3] = d.cam_xpos[cam]
            T.flags.writeable = False
            images[name] = CameraImage(name, rgb, depth, self._intrinsics[name])
            truth[name] = T
        return Frames(time_s, images, time.perf_counter() - start, truth)

    def _add_stereo_noise(self, depth: np.ndarray, fx_px: float) -> None:
        """Depth as a stereo pair measures it: disparity fx b / z [px] plus Gaussian noise, back to depth."""
        hit = np.isfinite(depth)
        fb = fx_px * self._baseline_m
        disparity = fb / depth[hit] + self._rng.normal(0.0, self._disparity_noise_px, int(hit.sum()))
        depth[hit] = np.where(disparity > 0, fb / np.maximum(disparity, 1e-9), np.inf)

    def _close(self) -> None:
        self._gl_thread_ids.add(threading.get_ident())
        self._renderer.close()

    # ------------------------------------------------------------------ callers' side

    @property
    def cameras(self) -> tuple[str, ...]:
        return self._cameras

    @property
    def intrinsics(self) -> dict[str, CameraIntrinsics]:
        return dict(self._intrinsics)

    @property
    def gl_thread_ids(self) -> frozenset[int]:
        """Identifiers of the threads that have touched the GL context (one: the render thread)."""
        return frozenset(self._gl_thread_ids)

    def request(self, qpos, time_s: float, mocap_pos=None, mocap_quat=None,
                cameras: Sequence[str] | None = None, analyse: Analysis | None = None) -> Future:
        """Queue a rendering of this state; the arrays are copied now, so the caller may go on stepping.

        qpos (nq,); mocap_pos (nmocap, 3) and mocap_quat (nmocap, 4) for fixed objects (None: the model's
        poses); cameras: a subset of the rig's (None: all). The future's result is a Frames, or with `analyse`
        = (fn, args) what fn(frames, *args) returns, computed where the image was rendered (check_analysis).
        """
        q, pos, quat, chosen = _copied_request(qpos, mocap_pos, mocap_quat, cameras, self._cameras)
        _check_request(q, pos, quat, chosen, self._model.nq, self._model.nmocap, self._cameras)
        check_analysis(analyse)
        with self._lock:
            if self._closed:
                raise RuntimeError("CameraRig is closed")
            return self._executor.submit(_analysed, self._render, (q, float(time_s), pos, quat, chosen), analyse)

    def request_state_of(self, data: mujoco.MjData, cameras: Sequence[str] | None = None,
                         analyse: Analysis | None = None) -> Future:
        """request() with a copy of this MjData's qpos, time and mocap poses (e.g. MujocoPlant.data)."""
        return self.request(data.qpos, data.time, data.mocap_pos, data.mocap_quat, cameras, analyse)

    def render(self, qpos, time_s: float, mocap_pos=None, mocap_quat=None,
               cameras: Sequence[str] | None = None) -> Frames:
        """request(...) and wait for it."""
        return self.request(qpos, time_s, mocap_pos, mocap_quat, cameras).result()

    def close(self) -> None:
        """Free the renderer on its thread and stop the thread (pending requests finish first). Idempotent."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        try:
            self._executor.submit(self._close).result()
        finally:
            self._executor.shutdown(wait=True)

    def __enter__(self) -> CameraRig:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


#: CameraProcess: the child must have made its renderer within this [s], and answer a request within this [s].
START_TIMEOUT_S = 60.0
FRAME_TIMEOUT_S = 20.0


#: A caller's analysis of a rendering, run where the image is: (fn, args), fn(frames, *args) -> a small result.
Analysis = tuple[Callable[..., Any], tuple]


def check_analysis(analyse: Analysis | None) -> None:
    """An analysis must be a module-level function (a camera process imports it by name) and a tuple of args."""
    if analyse is None:
        return
    fn, args = analyse
    if not (callable(fn) and getattr(fn, "__module__", None) and "<" not in getattr(fn, "__qualname__", "<")):
        raise ValueError(f"analyse: {fn!r} is not a module-level function (one a process can import by name)")
    if not isinstance(args, tuple):
        raise ValueError(f"analyse: the arguments must be a tuple, not {type(args).__name__}")


#: how much lower the camera process's priority is than the robot's by default (Linux nice increment; 10: the
#: scheduler gives it ~1/10 of a core the loop also wants). A loop that runs SCHED_FIFO preempts it whatever its
#: nice: its owner then passes nice=0 (robot.camera.CameraProcess), so that a busy machine does not starve it.
CAMERA_NICE = 10


def _analysed(render, request: tuple, analyse: Analysis | None):
    frames = render(*request)
    if analyse is None:
        return frames
    fn, args = analyse
    return fn(frames, *args)


def _serve(conn, scene_file: str, cameras: tuple[str, ...], width: int, height: int,
           depth_cameras: tuple[str, ...] | None, disparity_noise_px: float, seed: int | None,
           prepare: Callable[[], Any] | None = None, nice: int = CAMERA_NICE) -> None:
    """The camera process: a CameraRig of its own, rendering each request it receives until None arrives.

    It runs at a lower priority than the robot's process: never real-time (a real-time parent's SCHED_FIFO,
    inherited, made its renderer's threads hold the loop's core for 3-4 ms at each render), and at `nice`
    (+CAMERA_NICE unless the loop is real-time), both set before the renderer starts its threads, which
    inherit them; so rendering and analysing wait for the control loop instead of taking its core."""
    try:
        if os.sched_getscheduler(0) in (os.SCHED_FIFO, os.SCHED_RR):  # a real-time parent's, inherited
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        if nice:
            os.nice(nice)
    except OSError:
        pass  # not allowed here: equal priority
    try:
        rig = CameraRig(scene_file, cameras, width, height, depth_cameras, disparity_noise_px, seed)
    except Exception as err:  # noqa: BLE001 - reported to the parent, which raises it in the requests
        conn.send(("error", f"{type(err).__name__}: {err}"))
        return
    if prepare is not None:
        try:
            prepare()  # what the analyses need, loaded before the first request rather than by it
        except Exception as err:  # noqa: BLE001 - the analysis that needs it will fail with its own error
            logging.getLogger(__name__).warning("camera process: prepare %s failed: %s", prepare, err)
    m = rig._model
    conn.send(("ready", (m.nq, m.nmocap, rig.intrinsics)))
    with rig:
        while True:
            try:
                msg = conn.recv()
            except (EOFError, OSError):
                return  # the parent has gone
            if msg is None:
                return
            try:
                request, analyse = msg
                conn.send(("ok", _analysed(rig.render, request, analyse)))
            except Exception as err:  # noqa: BLE001 - one request's failure, reported in its future
                conn.send(("error", f"{type(err).__name__}: {err}"))


class CameraProcess:
    """CameraRig's interface with the renderer in a child process of its own.

    Why: MuJoCo's renderer holds Python's interpreter lock while it works. A render thread in the robot's
    process therefore stops the control loop too: measured here, making the EGL context ~0.5 s and each 640 x
    480 colour + depth frame 2-5 ms, during which no tick can start. In a child process only the copies of the
    request (qpos, mocap poses) and of the images (~2 MB) cost the parent, on its pipe thread that waits on the
    pipe without the lock. The child is spawned at construction and makes its renderer meanwhile: requests
    queue behind it (the first one waits the ~1-2 s the child needs to start).

    `model`, the scene's model in the parent (the plant's) if it has one: its sizes check the requests at once
    and give the intrinsics; the child loads `scene` itself. Without it (None: loading a model takes the lock
    for ~0.1 s) the child's ready message gives them, and a request made before that is checked on the pipe
    thread. Bad requests raise ValueError (in the future when checked there); a failure in the child (no
    renderer, a crash) fails the requests' futures with RuntimeError. `prepare`, a module-level function the
    child calls once before it answers (loading what the analyses need, so that the first one is not slower).
    `nice`, the child's nice increment (see CAMERA_NICE).
    """

    def __init__(self, scene: str | Path, model: mujoco.MjModel | None, cameras: Sequence[str] = HEAD_CAMERAS,
                 width: int = 640, height: int = 480, depth_cameras: Sequence[str] | None = None,
                 disparity_noise_px: float = 0.0, seed: int | None = None,
                 prepare: Callable[[], Any] | None = None, nice: int = CAMERA_NICE) -> None:
        import multiprocessing

        cameras = tuple(cameras)
        if not cameras:
            raise ValueError("cameras must name at least one camera")
        self._cameras = cameras
        self._nq: int | None = None
        self._nmocap: int | None = None
        self._intrinsics: dict[str, CameraIntrinsics] | None = None
        if model is not None:
            known = [model.camera(i).name for i in range(model.ncam)]
            unknown = [c for c in (*cameras, *(depth_cameras or ())) if c not in known]
            if unknown:
                raise ValueError(f"unknown camera(s) {unknown}; valid cameras: {', '.join(known)}")
            self._nq, self._nmocap = model.nq, model.nmocap
            self._intrinsics = {name: camera_intrinsics(model, name, width, height) for name in cameras}
        if prepare is not None:
            check_analysis((prepare, ()))
        ctx = multiprocessing.get_context("spawn")  # no fork of a process with threads and a GL context
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_serve, name="camera-render", daemon=True, args=(
            child, str(scene_path(scene)), cameras, width, height,
            None if depth_cameras is None else tuple(depth_cameras), float(disparity_noise_px), seed, prepare,
            int(nice)))
        self._ready = False
        self._lock = threading.Lock()
        self._closed = False
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="camera-pipe")
        # started on the pipe thread too (spawning takes 10-40 ms): the constructor returns at once
        self._executor.submit(self._start, child)

    def _start(self, child) -> None:
        self._proc.start()
        child.close()

    def __repr__(self) -> str:
        return f"CameraProcess(cameras={self._cameras}, pid={self._proc.pid}, closed={self._closed})"

    @property
    def cameras(self) -> tuple[str, ...]:
        return self._cameras

    @property
    def intrinsics(self) -> dict[str, CameraIntrinsics]:
        if self._intrinsics is None:
            self.wait_ready()
        return dict(self._intrinsics)

    @property
    def pid(self) -> int | None:
        return self._proc.pid

    def _receive(self, timeout_s: float) -> Any:
        deadline = time.monotonic() + timeout_s
        try:
            while not self._conn.poll(0.5):  # (no hang on a child that is gone or never starts)
                if not self._proc.is_alive():
                    raise EOFError
                if time.monotonic() > deadline:
                    raise RuntimeError(f"the camera process did not answer within {timeout_s:g} s (a script that "
                                       "starts it needs `if __name__ == '__main__':`: the child imports it)")
            kind, payload = self._conn.recv()
        except (EOFError, OSError):
            raise RuntimeError(f"the camera process ended (exit code {self._proc.exitcode})") from None
        if kind == "error":
            raise RuntimeError(f"camera process: {payload}")
        return payload

    def _ensure_ready(self) -> None:
        if not self._ready:
            nq, nmocap, intrinsics = self._receive(START_TIMEOUT_S)  # "ready": the child's renderer exists
            if self._nq is None:
                self._nq, self._nmocap = nq, nmocap
                self._intrinsics = {name: intrinsics[name] for name in self._cameras}
            self._ready = True

    def wait_ready(self, timeout_s: float = 60.0) -> None:
        """Block until the child has started and made its renderer (raises RuntimeError if it could not)."""
        self._executor.submit(self._ensure_ready).result(timeout_s)

    def _roundtrip(self, msg: tuple, analyse: Analysis | None):
        self._ensure_ready()
        self._check(*msg)
        try:
            self._conn.send((msg, analyse))
        except OSError:  # a broken pipe: the child is gone
            self._proc.join(1.0)
            raise RuntimeError(f"the camera process ended (exit code {self._proc.exitcode})") from None
        result = self._receive(FRAME_TIMEOUT_S)
        if analyse is None:
            for image in result.images.values():  # read-only, as CameraRig's
                image.rgb.flags.writeable = False
                if image.depth_m is not None:
                    image.depth_m.flags.writeable = False
        return result

    def request(self, qpos, time_s: float, mocap_pos=None, mocap_quat=None,
                cameras: Sequence[str] | None = None, analyse: Analysis | None = None) -> Future:
        """As CameraRig.request: the arrays are copied now; the future's result is a Frames, or with `analyse`
        what fn(frames, *args) returns, computed in the camera process: the image never crosses into this one
        (a recognition costs this process a small request and a small result, not ~2 MB of pixels)."""
        q, pos, quat, chosen = _copied_request(qpos, mocap_pos, mocap_quat, cameras, self._cameras)
        msg = (q, float(time_s), pos, quat, chosen)
        if self._nq is not None:
            self._check(*msg)
        check_analysis(analyse)
        with self._lock:
            if self._closed:
                raise RuntimeError("CameraProcess is closed")
            return self._executor.submit(self._roundtrip, msg, analyse)

    def _check(self, q, time_s, pos, quat, chosen) -> None:
        _check_request(q, pos, quat, chosen, self._nq, self._nmocap, self._cameras)

    def request_state_of(self, data: mujoco.MjData, cameras: Sequence[str] | None = None,
                         analyse: Analysis | None = None) -> Future:
        return self.request(data.qpos, data.time, data.mocap_pos, data.mocap_quat, cameras, analyse)

    def render(self, qpos, time_s: float, mocap_pos=None, mocap_quat=None,
               cameras: Sequence[str] | None = None) -> Frames:
        return self.request(qpos, time_s, mocap_pos, mocap_quat, cameras).result()

    def _stop_child(self) -> None:
        if self._proc.pid is None:
            return
        try:
            self._conn.send(None)
        except (OSError, ValueError):
            pass

    def close(self, timeout_s: float = 5.0) -> None:
        """Pending requests finish, the child ends (terminated after `timeout_s`). Idempotent."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        try:
            self._executor.submit(self._stop_child).result()
        finally:
            self._executor.shutdown(wait=True)
            if self._proc.pid is not None:  # (started)
                self._proc.join(timeout_s)
                if self._proc.is_alive():
                    self._proc.terminate()
                    self._proc.join(1.0)
            self._conn.close()

    def __enter__(self) -> CameraProcess:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
