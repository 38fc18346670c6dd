"""The viser 3D view: MuJoCo bodies moved from ground truth, E-STOP panel (with app/replay_viewer.py, which plays a
recorded session back with the same drawing, the only modules that import viser).

It runs in the console process: the geometry comes from the scene's model file, the poses from the robot's
published snapshots, and its buttons call the operator service like every other client. Its websocket only
accepts the console's own origins (a foreign page cannot drive the robot through it)."""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import deque

import mujoco
import numpy as np
import trimesh
import viser

from app.service import OperatorService, ServiceError
from app.viser_wakeup import wake_stuck_buffers
from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    distance_to_polygon_edge,
    support_polygon,
)
from controller.balance.leg_odometry import control_to_world
from controller.operation.targets import feet_frame, yaw_rotation
from robot.plant import scene_path

log = logging.getLogger(__name__)

_VISUAL_GROUPS = (0, 1, 2)  # MJCF geom groups drawn by default; group 3 holds the collision shapes
PLOT_WINDOW_S = 10.0  # [s] of simulated time shown by the capture-point error plot
PLOT_RATE_HZ = 25.0  # plot samples and redraws per second (wall time): the issue asks >= 20
WAKE_PERIOD_S = 0.5  # [s] how often a viser sender that missed its wake-up is looked for (app/viser_wakeup.py)
PLOT_RANGE_MM = 100.0  # the plot's fixed y range +-[mm]: the default 40 mm threshold stays readable
OP_TARGET_POINTS = ("rhand", "lhand")  # operational points whose target position is drawn (x, y, z in F)
MAX_FOOTSTEPS = 16  # planned footsteps drawn (fixed buffer: the handles are only updated, never rebuilt)
_FLOOR_LIFT_M = 0.002  # floor markers drawn this far above the sole plane so they are not hidden
FOLLOWED_BODY = "BODY"  # the body the 3D view's camera follows
FOLLOW_STEP_M = 0.002  # [m] the camera is moved once the body has gone this far (not at every sway)
_SOLES = {"rleg": HRP2_RIGHT_SOLE, "lleg": HRP2_LEFT_SOLE}


def _rgb_opacity(rgba: np.ndarray) -> tuple[tuple[int, int, int], float | None]:
    rgb = tuple(int(round(255 * float(np.clip(c, 0.0, 1.0)))) for c in rgba[:3])
    alpha = float(rgba[3])
    return rgb, (None if alpha >= 0.999 else max(alpha, 0.05))


def geom_mesh(model: mujoco.MjModel, g: int) -> trimesh.Trimesh | None:
    """The triangle mesh of geom `g` in its own frame, or None for types drawn otherwise (box, plane)."""
    typ, size = model.geom_type[g], model.geom_size[g]
    if typ == mujoco.mjtGeom.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=2, radius=float(size[0]))
    if typ == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        m = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        m.apply_scale(np.asarray(size[:3], dtype=float))
        return m
    if typ == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return trimesh.creation.capsule(height=2.0 * float(size[1]), radius=float(size[0]), count=[16, 8])
    if typ == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=float(size[0]), height=2.0 * float(size[1]), sections=24)
    if typ == mujoco.mjtGeom.mjGEOM_MESH:
        mid = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
        f0, nf = model.mesh_faceadr[mid], model.mesh_facenum[mid]
        return trimesh.Trimesh(vertices=model.mesh_vert[v0:v0 + nv].copy(),
                               faces=model.mesh_face[f0:f0 + nf].copy(), process=False)
    return None


def _yaw(R) -> float:
    R = np.asarray(R, dtype=float)
    return float(math.atan2(R[1, 0], R[0, 0]))


def _closed_segments(xy: np.ndarray, z: float) -> np.ndarray:
    """(M, 2, 3) segments of the closed polygon through the (M, 2) points `xy` at height z."""
    p = np.column_stack([xy, np.full(len(xy), z)])
    return np.stack([p, np.roll(p, -1, axis=0)], axis=1)


def _padded(segments: np.ndarray, n: int) -> np.ndarray:
    """Exactly n segments: the extra slots repeat the last real one (drawn over it, so invisible)."""
    segments = segments[:n]
    if len(segments) < n:
        segments = np.concatenate([segments, np.repeat(segments[-1:], n - len(segments), axis=0)])
    return segments.astype(np.float32)


def footstep_rectangles(steps, z: float) -> np.ndarray:
    """(4 * len(steps), 2, 3) outline segments of footsteps given as {"leg", "pos": [3], "yaw"} [m, rad]."""
    segs = []
    for step in steps:
        rect = _SOLES.get(str(step.get("leg")), HRP2_RIGHT_SOLE)
        pos = np.asarray(step.get("pos", (0.0, 0.0, z)), dtype=float)
        corners = rect.corners_world((pos[0], pos[1], float(step.get("yaw", 0.0))))
        segs.append(_closed_segments(corners, (float(pos[2]) if len(pos) > 2 else z) + _FLOOR_LIFT_M))
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def ray_at_height(origin, direction, z_m: float) -> np.ndarray | None:
    """Where the ray origin + t direction (t > 0) crosses the horizontal plane z = z_m (world [m]); None when it
    runs parallel to it or away from it."""
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    if abs(d[2]) < 1e-9:
        return None
    t = (float(z_m) - o[2]) / d[2]
    return None if t <= 0 else o + t * d


def support_edge_mm(snap) -> float | None:
    """Distance [mm] from the reference capture point to the edge of the support polygon of the soles in contact
    (the planned ones): the error at which the actual capture point would leave the support, in the worst
    direction. None without a gait reference or a Stabilizer."""
    gait = getattr(getattr(snap, "reference", None), "gait", None)
    st = snap.layers.get("st")
    if gait is None or st is None or getattr(st, "cp_ref", None) is None:
        return None
    feet = [((p[0], p[1], _yaw(R)), rect) for p, R, rect, on in (
        (gait.p_rsole_world, gait.R_rsole_world, HRP2_RIGHT_SOLE, gait.contact[0]),
        (gait.p_lsole_world, gait.R_lsole_world, HRP2_LEFT_SOLE, gait.contact[1])) if on]
    if not feet:
        return None
    return 1e3 * max(0.0, distance_to_polygon_edge(st.cp_ref, support_polygon(feet)))


class CpErrorHistory:
    """Ring buffer of (sim time [s], CP error x, y [mm], threshold [mm], flag, support edge [mm]) over the last
    `window_s`."""

    def __init__(self, window_s: float = PLOT_WINDOW_S, maxlen: int = 2000) -> None:
        self.window_s = float(window_s)
        self._rows: deque[tuple[float, ...]] = deque(maxlen=maxlen)
        self._lock = threading.Lock()  # the viewer's thread and a caller may add the same snapshot at once

    def __len__(self) -> int:
        return len(self._rows)

    def add(self, snap) -> bool:
        """Sample the snapshot's Stabilizer status; False when it has none. A reset clears the buffer."""
        st = snap.layers.get("st")
        if st is None:
            return False
        t = float(snap.time_s)
        ex, ey = st.cp_error
        edge = support_edge_mm(snap)
        with self._lock:
            rows = self._rows
            if rows and t < rows[-1][0]:
                rows.clear()  # the simulation was reset
            if rows and t == rows[-1][0]:
                return False
            if edge is None:  # no gait reference: the last known edge, else the plot's range
                edge = rows[-1][5] if rows else PLOT_RANGE_MM
            rows.append((t, 1e3 * float(ex), 1e3 * float(ey), 1e3 * float(st.cp_threshold_m),
                         1.0 if st.emergency else 0.0, min(float(edge), PLOT_RANGE_MM)))
            while rows and rows[0][0] < t - self.window_s:
                rows.popleft()
        return True

    def latest(self) -> tuple[float, float, float, float, bool] | None:
        """The newest row: (time [s], err x, err y, threshold [mm], flag), or None."""
        if not self._rows:
            return None
        t, ex, ey, thr, flag, _ = self._rows[-1]
        return t, ex, ey, thr, bool(flag)

    def data(self) -> tuple[np.ndarray, ...]:
        """(time, err x, err y, +threshold, -threshold, +support edge, -support edge, flag band) arrays for the
        uPlot; the flag band is at the top of the fixed range while the CP flag is raised and at its bottom
        otherwise (filled down: shaded)."""
        with self._lock:
            if not self._rows:
                z = np.zeros(1)
                return z, z, z, z, z, z, z, np.full(1, -PLOT_RANGE_MM)
            a = np.asarray(self._rows, dtype=float)
        band = np.where(a[:, 4] > 0.5, PLOT_RANGE_MM, -PLOT_RANGE_MM)
        return (a[:, 0].copy(), a[:, 1].copy(), a[:, 2].copy(), a[:, 3].copy(), -a[:, 3], a[:, 5].copy(), -a[:, 5],
                band)


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


def _geom_color(model: mujoco.MjModel, g: int) -> np.ndarray:
    mat = model.geom_matid[g]
    if mat >= 0 and np.allclose(model.geom_rgba[g], [0.5, 0.5, 0.5, 1.0]):
        return np.asarray(model.mat_rgba[mat])  # the MJCF default rgba: the material decides
    return np.asarray(model.geom_rgba[g])


class _OriginCheckingServe:
    """Stands in for `websockets.asyncio.server.serve` inside viser: the same call with a request check in
    front of viser's own, so the handshake of a page from another origin is refused (403) before viser sees
    it (app.security.origin_allowed: the viewer's own port, the port the connection arrived on, or the operator
    page's, on the bound host or a loopback name)."""

    def __init__(self, serve, host: str, page_ports: set[int]):
        from app.security import allowed_hosts_for

        self._serve = serve
        hosts = allowed_hosts_for(host)
        self._hosts = None if hosts is None else frozenset(hosts)
        self._page_ports = page_ports

    def __call__(self, handler, host, port, **kwargs):
        from app.security import origin_allowed, repeated_header

        inner = kwargs.get("process_request")
        hosts, page_ports = self._hosts, self._page_ports

        def process_request(connection, request):
            headers = request.headers
            repeated = repeated_header(headers.raw_items())
            if repeated is not None:
                return connection.respond(400, f"header {repeated} given more than once\n")
            if headers.get("Upgrade", "").lower() == "websocket":
                ports = {connection.local_address[1], *page_ports}
                if not origin_allowed(headers.get("Origin"), headers.get("Host", ""), hosts, ports):
                    return connection.respond(403, "this viewer only accepts its own page\n")
            return inner(connection, request) if inner is not None else None

        kwargs["process_request"] = process_request
        return self._serve(handler, host, port, **kwargs)


def _viser_with_origin_check(host: str, port: int, page_ports: set[int], **kwargs) -> viser.ViserServer:
    """A ViserServer whose websocket checks the Origin header (viser 1.1 has no option for it: its server
    module's reference to websockets' `serve` is wrapped while the server starts)."""
    import types

    from viser.infra import _infra

    real = _infra.websockets
    wrapped = types.SimpleNamespace(**{k: getattr(real, k) for k in ("datastructures", "exceptions")})
    wrapped.asyncio = types.SimpleNamespace(server=types.SimpleNamespace(
        serve=_OriginCheckingServe(real.asyncio.server.serve, host, page_ports),
        ServerConnection=real.asyncio.server.ServerConnection))
    _infra.websockets = wrapped
    try:
        server = viser.ViserServer(host=host, port=port, verbose=False, **kwargs)
    finally:
        _infra.websockets = real
    return server


def add_model(scene, model: mujoco.MjModel) -> tuple[list, list]:
    """Draw a MuJoCo model's bodies in a viser scene: one frame per moving body ("/bodies/<name>", placed later
    from body poses) holding its visual geoms (or its collision geoms when it has no visual one), the world's geoms
    under "/static". Returns (the frames of bodies 1..nbody-1, every node made)."""
    names = tuple(model.body(b).name for b in range(model.nbody))
    has_visual = np.zeros(model.nbody, dtype=bool)
    for g in range(model.ngeom):
        if model.geom_group[g] in _VISUAL_GROUPS:
            has_visual[model.geom_bodyid[g]] = True
    frames, nodes = [], []
    for b in range(1, model.nbody):
        frame = scene.add_frame(f"/bodies/{names[b]}", show_axes=False)
        frames.append(frame)
        nodes.append(frame)
    for g in range(model.ngeom):
        b = model.geom_bodyid[g]
        if (model.geom_group[g] in _VISUAL_GROUPS) != bool(has_visual[b]):
            continue  # draw the visual geoms, or the collision ones of bodies that have no visual
        parent = "/static" if b == 0 else f"/bodies/{names[b]}"
        node = add_geom(scene, model, g, f"{parent}/geom{g}")
        if node is not None:
            nodes.append(node)
    return frames, nodes


def add_geom(scene, model: mujoco.MjModel, g: int, name: str):
    """One geom in a viser scene (grid for a plane, box, or a triangle mesh), in its body's frame."""
    pos = np.asarray(model.geom_pos[g], dtype=float)
    wxyz = np.asarray(model.geom_quat[g], dtype=float)
    rgb, opacity = _rgb_opacity(_geom_color(model, g))
    typ = model.geom_type[g]
    if typ == mujoco.mjtGeom.mjGEOM_PLANE:
        size = model.geom_size[g]
        width = float(2 * size[0]) if size[0] > 0 else 10.0
        height = float(2 * size[1]) if size[1] > 0 else 10.0
        return scene.add_grid(name, width=width, height=height, cell_size=0.25, section_size=1.0,
                              plane_color=(200, 205, 215), plane_opacity=1.0, shadow_opacity=0.0,
                              position=pos, wxyz=wxyz)
    if typ == mujoco.mjtGeom.mjGEOM_BOX:
        return scene.add_box(name, color=rgb, dimensions=2.0 * np.asarray(model.geom_size[g], dtype=float),
                             opacity=opacity, cast_shadow=False, receive_shadow=False, position=pos, wxyz=wxyz)
    mesh = geom_mesh(model, g)
    if mesh is None:
        log.debug("geom %d of type %d not drawn", g, typ)
        return None
    return scene.add_mesh_simple(name, vertices=np.asarray(mesh.vertices), faces=np.asarray(mesh.faces),
                                 color=rgb, opacity=opacity, cast_shadow=False, receive_shadow=False,
                                 position=pos, wxyz=wxyz)


class Viewer:
    """viser server showing the robot; body poses are pushed in one atomic batch at `rate_hz`."""

    def __init__(self, service: OperatorService, host: str = "127.0.0.1", port: int = 8080, rate_hz: float = 25.0):
        self.service = service
        self.rate_hz = float(rate_hz)
        self._host = host
        self._page_ports: set[int] = set()
        self.server = _viser_with_origin_check(host, port, self._page_ports)
        self.port = self.server.get_port()
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self.server.scene.set_up_direction("+z")
        self._frames: list[viser.FrameHandle] = []
        self._scene_nodes: list = []
        self._model_key: tuple[str, ...] = ()
        self._model: mujoco.MjModel | None = None
        self._cp_history = CpErrorHistory()
        self._recognition_markers: dict[str, tuple] = {}  # object -> (sphere, label, position shown)
        self._plot_updates = 0
        self._follower = CameraFollower()
        self._build_markers()
        self._build_scene()
        self._build_gui()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="viser-update", daemon=True)
        self._thread.start()

    def allow_page(self, port: int) -> None:
        """Accept the websocket of the operator page served on `port` of the same host (its /viewer/ iframe)."""
        self._page_ports.add(int(port))

    # ---- scene --------------------------------------------------------------------------------
    def _build_scene(self) -> None:
        for node in self._scene_nodes:
            node.remove()
        model = mujoco.MjModel.from_xml_path(str(scene_path(self.service.info.scene)))
        self._model = model
        self._scene = self.service.info.scene
        names = tuple(model.body(b).name for b in range(model.nbody))
        self._model_key = names
        self._followed = names.index(FOLLOWED_BODY) if FOLLOWED_BODY in names else None
        self._frames, self._scene_nodes = add_model(self.server.scene, model)
        try:
            self._apply_poses(self.service.observation().truth)
        except ServiceError:
            pass

    def _apply_poses(self, truth) -> None:
        with self.server.atomic():
            self._set_body_poses(truth)

    def _set_body_poses(self, truth) -> None:
        pos, quat = truth.body_pos_world, truth.body_quat_wxyz
        for b, frame in enumerate(self._frames, start=1):
            frame.position = pos[b]
            frame.wxyz = quat[b]

    def apply_snapshot(self, snap) -> None:
        """Body poses and the balance markers of one observation (a snapshot with the ground truth beside it),
        in one atomic batch."""
        with self.server.atomic():
            self._set_body_poses(snap.truth)
            self._update_markers(snap)

    # ---- balance markers: built once, then only moved / shown / hidden ---------------------------
    def _build_markers(self) -> None:
        scene = self.server.scene
        m: dict = {}
        m["cog"] = scene.add_icosphere("/markers/cog", radius=0.03, color=(255, 140, 0), subdivisions=2,
                                       cast_shadow=False, receive_shadow=False)
        m["zmp"] = scene.add_cylinder("/markers/zmp", radius=0.02, height=0.004, color=(40, 200, 60),
                                      radial_segments=16, cast_shadow=False, receive_shadow=False)
        m["cp_ref"] = scene.add_icosphere("/markers/cp_ref", radius=0.015, color=(30, 110, 255), subdivisions=1,
                                          cast_shadow=False, receive_shadow=False)
        m["cp_act"] = scene.add_icosphere("/markers/cp_act", radius=0.015, color=(230, 30, 60), subdivisions=1,
                                          cast_shadow=False, receive_shadow=False)
        seg = np.zeros((1, 2, 3), dtype=np.float32)
        m["support"] = scene.add_line_segments("/markers/support_polygon", _padded(seg, 8), (255, 215, 0),
                                               thickness=0.004, visible=False)
        m["soles"] = scene.add_line_segments("/markers/soles", _padded(seg, 8), (90, 90, 110),
                                             thickness=0.003, visible=False)
        m["footsteps"] = scene.add_line_segments("/markers/footsteps", _padded(seg, 4 * MAX_FOOTSTEPS),
                                                 (0, 170, 200), thickness=0.003, visible=False)
        for point, color in zip(OP_TARGET_POINTS, ((200, 40, 200), (120, 40, 220)), strict=True):
            m[f"target_{point}"] = scene.add_icosphere(f"/markers/target_{point}", radius=0.025, color=color,
                                                       subdivisions=1, opacity=0.6, cast_shadow=False,
                                                       receive_shadow=False, visible=False)
        self._markers = m

    @staticmethod
    def _show(handle, visible: bool) -> None:
        if handle.visible != visible:
            handle.visible = visible

    def _place(self, handle, pos) -> None:
        p = np.asarray(pos, dtype=float)
        ok = p.shape == (3,) and bool(np.all(np.isfinite(p)))
        if ok:
            handle.position = p
        self._show(handle, ok)

    def _update_markers(self, snap) -> None:
        """The balance markers, computed in the controller's frame (the gait plan's), drawn in the world of leg
        odometry (`snap.odometry.world_from_control`) beside the robot drawn from the simulation: the plan's frame
        drifts from the world with the landings it never sees (19 mm after 1 m of walking), the odometry stays
        within about a millimetre."""
        m = self._markers
        odometry = getattr(snap, "odometry", None)
        wfc = None if odometry is None else odometry.world_from_control
        to_world = (lambda p: p) if wfc is None else (lambda p: np.asarray(control_to_world(wfc, p)))
        dyaw = 0.0 if wfc is None else float(wfc[3])
        gait = getattr(snap.reference, "gait", None)
        zmp = np.asarray(snap.zmp_world, dtype=float)
        if gait is not None:
            floor_z = 0.5 * (float(gait.p_rsole_world[2]) + float(gait.p_lsole_world[2]))
        else:
            floor_z = float(zmp[2]) if np.isfinite(zmp[2]) else 0.0
        self._place(m["cog"], to_world(np.asarray(snap.cog_world, dtype=float)))
        self._place(m["zmp"], to_world((zmp[0], zmp[1], floor_z + _FLOOR_LIFT_M)))
        st = snap.layers.get("st")
        for key in ("cp_ref", "cp_act"):
            xy = getattr(st, key, None)
            if xy is None:
                self._show(m[key], False)
            else:
                self._place(m[key], to_world((float(xy[0]), float(xy[1]), floor_z + 2 * _FLOOR_LIFT_M)))
        if gait is None:
            for key in ("support", "soles"):
                self._show(m[key], False)
        else:
            soles = [(to_world(p), _yaw(R) + dyaw) for p, R in ((gait.p_rsole_world, gait.R_rsole_world),
                                                              (gait.p_lsole_world, gait.R_lsole_world))]
            feet = [((p[0], p[1], yaw), rect) for (p, yaw), rect in zip(soles, (HRP2_RIGHT_SOLE, HRP2_LEFT_SOLE),
                                                                        strict=True)]
            steps = [{"leg": leg, "pos": p, "yaw": yaw} for leg, (p, yaw) in zip(("rleg", "lleg"), soles, strict=True)]
            m["soles"].points = _padded(footstep_rectangles(steps, floor_z), 8)
            self._show(m["soles"], True)
            in_contact = [f for f, on in zip(feet, gait.contact, strict=True) if on]
            if in_contact:
                poly = support_polygon(in_contact)
                m["support"].points = _padded(_closed_segments(poly, floor_z + _FLOOR_LIFT_M), 8)
            self._show(m["support"], bool(in_contact))
        abc = snap.layers.get("abc")
        planned = [{"leg": f.leg, "pos": to_world(f.pos), "yaw": f.rpy[2] + dyaw}
                   for f in (abc.footsteps if abc is not None else ())]
        if planned:
            m["footsteps"].points = _padded(footstep_rectangles(planned[:MAX_FOOTSTEPS], floor_z),
                                            4 * MAX_FOOTSTEPS)
        self._show(m["footsteps"], bool(planned))
        self._update_targets(snap, gait, to_world)

    def _update_targets(self, snap, gait, to_world) -> None:
        """The operation layer's hand targets (x, y, z in the feet frame F) drawn in the world (`to_world`: a
        point of the controller's frame in the world)."""
        op = snap.layers.get("op")
        points = getattr(op, "points", None) or {}
        frame = None
        if gait is not None:
            frame = feet_frame(gait.p_rsole_world, gait.R_rsole_world, gait.p_lsole_world, gait.R_lsole_world)
        for point in OP_TARGET_POINTS:
            handle = self._markers[f"target_{point}"]
            status = points.get(point)
            target = getattr(status, "target", None)
            if frame is None or target is None:
                self._show(handle, False)
                continue
            origin, yaw = frame
            self._place(handle, to_world(origin + yaw_rotation(yaw) @ np.asarray(target[:3], dtype=float)))

    def _update_recognitions(self, recognitions) -> None:
        """A marker and a label at each located object's position (the operator's correction once given)."""
        scene = self.server.scene
        for name in list(self._recognition_markers):
            if name not in recognitions:  # a reset forgot it
                for handle in reversed(self._recognition_markers.pop(name)[:2]):
                    handle.remove()
        for name, rec in recognitions.items():
            pos = tuple(float(v) for v in rec.get("position_m", ()))
            if len(pos) != 3 or not all(math.isfinite(v) for v in pos):
                continue
            status = rec.get("status", "estimated")
            shown = self._recognition_markers.get(name)
            if shown is not None and shown[2] == (pos, status):
                continue
            if shown is not None:
                for handle in reversed(shown[:2]):
                    handle.remove()
            color = (40, 170, 60) if status != "estimated" else (255, 200, 0)
            sphere = scene.add_icosphere(f"/recognitions/{name}", radius=0.04, color=color, subdivisions=2,
                                         opacity=0.7, position=pos, cast_shadow=False, receive_shadow=False)
            sigma = rec.get("sigma_m") or [0.0, 0.0]
            label = scene.add_label(f"/recognitions/{name}/label",
                                    f"{name} ({status}, sigma {1e3 * math.hypot(*sigma[:2]):.0f} mm)",
                                    position=(0.0, 0.0, 0.1))
            self._recognition_markers[name] = (sphere, label, (pos, status))

    # ---- GUI ----------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.server.gui
        gui.add_markdown("**HRP-2 No.10**: operator e-stop")
        self._estop = gui.add_button("E-STOP", color="red", icon=None, hint="Freeze the joint command now")
        self._release = gui.add_button("Release", color="gray", hint="Release the hard e-stop")
        self._follow = gui.add_checkbox("follow the robot", True, hint="keep the view on the robot (BODY) as it "
                                        "walks; your orbit and zoom are kept")

        @self._follow.on_update
        def _(_event) -> None:
            self._follower.restart()
        self._time = gui.add_text("time [s]", "0.000", disabled=True)
        self._hard_stop = gui.add_checkbox("hard stop", False, disabled=True)
        self._fallen = gui.add_checkbox("fallen", False, disabled=True)
        self._fault = gui.add_text("fault", "none", disabled=True)
        self._message = gui.add_text("last action", "", disabled=True)
        try:
            self._cp_history.add(self.service.observation())
        except ServiceError:
            pass
        self._cp_plot = gui.add_uplot(
            self._cp_history.data(),
            ({"label": "t [s]"},
             {"label": "CP err x [mm]", "stroke": "#e6194b", "width": 1.5},
             {"label": "CP err y [mm]", "stroke": "#3c78d8", "width": 1.5},
             {"label": "+threshold", "stroke": "#888888", "width": 1, "dash": (6.0, 4.0)},
             {"label": "-threshold", "stroke": "#888888", "width": 1, "dash": (6.0, 4.0)},
             {"label": "+support edge", "stroke": "#b8860b", "width": 1, "dash": (2.0, 3.0)},
             {"label": "-support edge", "stroke": "#b8860b", "width": 1, "dash": (2.0, 3.0)},
             {"label": "CP flag", "stroke": "rgba(200,16,46,0)", "width": 0, "fill": "rgba(200,16,46,0.18)",
              "fillTo": -PLOT_RANGE_MM,
              "points": {"show": False}}),
            title="capture-point error [mm] (dashed grey: threshold; dotted: support edge; shaded: CP flag raised)",
            scales={"x": {"time": False}, "y": {"auto": False, "range": (-PLOT_RANGE_MM, PLOT_RANGE_MM)}},
            legend={"show": True, "live": True},
            aspect=1.6,
        )
        self._cp_values = gui.add_markdown(self._cp_legend())
        # [OP] II: the operator corrects a recognition by clicking where the object is (at its estimated height)
        self._correct_object = gui.add_dropdown("object", ("can", "trash_box"), initial_value="can")
        self._correct_click = gui.add_button("Correct it: click where it is", hint="then click the object in the "
                                             "3D view: its position becomes what later behaviours use")

        @self._correct_click.on_click
        def _(_event) -> None:
            name = self._correct_object.value

            @self.server.scene.on_pointer_event("click")
            def _(event) -> None:
                self.server.scene.remove_pointer_callback()
                self._message.value = self.correct_by_ray(name, event.ray_origin, event.ray_direction)

            self._message.value = f"click where the {name} is"

        @self._estop.on_click
        def _(_event) -> None:
            self.press_estop()

        @self._release.on_click
        def _(_event) -> None:
            self._command("e-stop released", self.service.release_estop)

    def correct_by_ray(self, name: str, origin, direction) -> str:
        """The recognition of `name` moved to where the clicked ray meets its estimated height; what it says."""
        try:
            rec = self.service.recognitions().get(name)
            if rec is None:
                return f"no recognition of {name} to correct (locate it first)"
            p = ray_at_height(origin, direction, float(rec["position_m"][2]))
            if p is None:
                return f"that click does not reach the {name}'s height ({rec['position_m'][2]:.3f} m)"
            self.service.confirm_recognition(name, [float(v) for v in p])
            return f"{name} corrected to ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m"
        except ServiceError as exc:
            return str(exc)

    def press_estop(self) -> None:
        """The panel's E-STOP: every click a new press (app.service.estop), the loop's answer shown."""
        self._command(None, lambda: self.service.estop().message)

    def _command(self, done: str | None, fn) -> None:
        """Runs in viser's thread pool: a verb of the operator service, like an HTTP request."""
        try:
            said = fn()
            self._message.value = done if done is not None else str(said)
        except ServiceError as exc:
            self._message.value = str(exc)
        except Exception as exc:  # noqa: BLE001 - a GUI click never kills anything
            log.exception("viewer command failed")
            self._message.value = f"{type(exc).__name__}: {exc}"

    def _update_gui(self, snap) -> None:
        t = f"{snap.time_s:.3f}"
        if self._time.value != t:
            self._time.value = t
        hard = bool(snap.safety.hard_stop)
        if self._hard_stop.value != hard:
            self._hard_stop.value = hard
        if self._fallen.value != bool(snap.fallen):
            self._fallen.value = bool(snap.fallen)
        fault = snap.fault or "none"
        if self._fault.value != fault:
            self._fault.value = fault

    def follow(self, truth) -> int:
        """The clients' cameras kept on the followed body (when the toggle is on); how many moved."""
        if not self._follow.value or self._followed is None:
            return 0
        clients = self.server.get_clients()
        return self._follower.update({cid: c.camera for cid, c in clients.items()},
                                     truth.body_pos_world[self._followed][:2], atomic=lambda cid: clients[cid].atomic())

    def _cp_legend(self) -> str:
        """The plot's current values, as a line under it (uPlot's own legend shows them under the cursor)."""
        row = self._cp_history.latest()
        if row is None:
            return "CP error: no Stabilizer"
        t, ex, ey, thr, flag = row
        return (f"t {t:.2f} s: x **{ex:+.1f}** mm, y **{ey:+.1f}** mm, |e| {math.hypot(ex, ey):.1f} / threshold "
                f"{thr:.1f} mm, flag **{'RAISED' if flag else 'off'}**")

    def _update_plot(self, snap) -> None:
        if self._cp_history.add(snap):
            self._cp_plot.data = self._cp_history.data()
            self._plot_updates += 1
            if self._plot_updates % 5 == 0:
                self._cp_values.content = self._cp_legend()

    # ---- background update ----------------------------------------------------------------------
    def _run(self) -> None:
        period = 1.0 / self.rate_hz
        last_tick, n = -1, 0
        due = time.monotonic()
        while True:  # on a fixed schedule (the work of a round does not stretch the period)
            due = max(due + period, time.monotonic())
            if self._stop.wait(due - time.monotonic()):
                break
            try:
                if self.service.info.scene != self._scene:
                    self._build_scene()  # the simulation was reset to another scene
                snap = self.service.observation()
                if snap.tick != last_tick:
                    self.apply_snapshot(snap)
                    self.follow(snap.truth)
                    last_tick = snap.tick
                n += 1
                if n % max(1, int(self.rate_hz / 5)) == 0:
                    self._update_gui(snap)
                    self._update_recognitions(self.service.recognitions())
                if n % max(1, round(self.rate_hz / PLOT_RATE_HZ)) == 0:
                    self._update_plot(snap)
                if n % max(1, round(self.rate_hz * WAKE_PERIOD_S)) == 0:
                    wake_stuck_buffers(self.server)  # viser 1.1.1's lost wake-up (app/viser_wakeup.py)
            except ServiceError:  # the robot process is gone or restarting: try again shortly
                time.sleep(0.5)
            except Exception:  # noqa: BLE001 - keep drawing whatever happens
                log.exception("viewer update failed")
                time.sleep(0.5)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.server.stop()
