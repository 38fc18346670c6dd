"""The viser 3D view (the only module that imports viser): MuJoCo bodies moved from ground truth, E-STOP panel."""

from __future__ import annotations

import logging
import threading
import time

import mujoco
import numpy as np
import trimesh
import viser

from app.runtime import Runtime
from controller.errors import ControllerError

log = logging.getLogger(__name__)

_VISUAL_GROUPS = (0, 1, 2)  # MJCF geom groups drawn by default; group 3 holds the collision shapes


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


def _geom_color(model: mujoco.MjModel, g: int) -> np.ndarray:
    mat = model.geom_matid[g]
    if mat >= 0 and np.allclose(model.geom_rgba[g], [0.5, 0.5, 0.5, 1.0]):
        return np.asarray(model.mat_rgba[mat])  # the MJCF default rgba: the material decides
    return np.asarray(model.geom_rgba[g])


class Viewer:
    """viser server showing the robot; body poses are pushed in one atomic batch at `rate_hz`."""

    def __init__(self, runtime: Runtime, host: str = "127.0.0.1", port: int = 8080, rate_hz: float = 30.0):
        self.runtime = runtime
        self.rate_hz = float(rate_hz)
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.port = self.server.get_port()
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self.server.scene.set_up_direction("+z")
        self._frames: list[viser.FrameHandle] = []
        self._scene_nodes: list = []
        self._model_key: tuple[str, ...] = ()
        self._model: mujoco.MjModel | None = None
        self._build_scene()
        self._build_gui()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="viser-update", daemon=True)
        self._thread.start()

    # ---- scene --------------------------------------------------------------------------------
    def _build_scene(self) -> None:
        for node in self._scene_nodes:
            node.remove()
        self._frames, self._scene_nodes = [], []
        model = self.runtime.loop.plant.model
        self._model = model
        names = tuple(model.body(b).name for b in range(model.nbody))
        self._model_key = names
        has_visual = np.zeros(model.nbody, dtype=bool)
        for g in range(model.ngeom):
            if model.geom_group[g] in _VISUAL_GROUPS:
                has_visual[model.geom_bodyid[g]] = True
        for b in range(1, model.nbody):
            frame = self.server.scene.add_frame(f"/bodies/{names[b]}", show_axes=False)
            self._frames.append(frame)
            self._scene_nodes.append(frame)
        for g in range(model.ngeom):
            b = model.geom_bodyid[g]
            if (model.geom_group[g] in _VISUAL_GROUPS) != bool(has_visual[b]):
                continue  # draw the visual geoms, or the collision ones of bodies that have no visual
            parent = "/static" if b == 0 else f"/bodies/{names[b]}"
            node = self._add_geom(model, g, f"{parent}/geom{g}")
            if node is not None:
                self._scene_nodes.append(node)
        self._apply_poses(self.runtime.loop.snapshot.truth)

    def _add_geom(self, model: mujoco.MjModel, g: int, name: str):
        pos = np.asarray(model.geom_pos[g], dtype=float)
        wxyz = np.asarray(model.geom_quat[g], dtype=float)
        rgb, opacity = _rgb_opacity(_geom_color(model, g))
        typ = model.geom_type[g]
        scene = self.server.scene
        if typ == mujoco.mjtGeom.mjGEOM_PLANE:
            size = model.geom_size[g]
            width = float(2 * size[0]) if size[0] > 0 else 10.0
            height = float(2 * size[1]) if size[1] > 0 else 10.0
            return scene.add_grid(name, width=width, height=height, cell_size=0.25, section_size=1.0,
                                  plane_color=(200, 205, 215), plane_opacity=1.0, shadow_opacity=0.0,
                                  position=pos, wxyz=wxyz)
        if typ == mujoco.mjtGeom.mjGEOM_BOX:
            return scene.add_box(name, color=rgb, dimensions=2.0 * np.asarray(model.geom_size[g], dtype=float),
                                 opacity=opacity, cast_shadow=False, receive_shadow=False,
                                 position=pos, wxyz=wxyz)
        mesh = geom_mesh(model, g)
        if mesh is None:
            log.debug("geom %d of type %d not drawn", g, typ)
            return None
        return scene.add_mesh_simple(name, vertices=np.asarray(mesh.vertices), faces=np.asarray(mesh.faces),
                                     color=rgb, opacity=opacity, cast_shadow=False, receive_shadow=False,
                                     position=pos, wxyz=wxyz)

    def _apply_poses(self, truth) -> None:
        pos, quat = truth.body_pos_world, truth.body_quat_wxyz
        with self.server.atomic():
            for b, frame in enumerate(self._frames, start=1):
                frame.position = pos[b]
                frame.wxyz = quat[b]

    # ---- GUI ----------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.server.gui
        gui.add_markdown("**HRP-2 No.10**: operator e-stop")
        self._estop = gui.add_button("E-STOP", color="red", icon=None, hint="Freeze the joint command now")
        self._release = gui.add_button("Release", color="gray", hint="Release the hard e-stop")
        self._time = gui.add_text("time [s]", "0.000", disabled=True)
        self._hard_stop = gui.add_checkbox("hard stop", False, disabled=True)
        self._fallen = gui.add_checkbox("fallen", False, disabled=True)
        self._fault = gui.add_text("fault", "none", disabled=True)
        self._message = gui.add_text("last action", "", disabled=True)

        @self._estop.on_click
        def _(_event) -> None:
            self._command("e-stop engaged", lambda loop: loop.chain["hes"].engage())

        @self._release.on_click
        def _(_event) -> None:
            def release(loop) -> None:
                loop.chain["hes"].release()
                loop.clear_fault()
            self._command("e-stop released", release)

    def _command(self, done: str, fn) -> None:
        """Runs in viser's thread pool: the command goes through the loop's queue like an HTTP one."""
        loop = self.runtime.loop
        try:
            self.runtime.call(lambda: fn(loop))
            self._message.value = done
        except ControllerError as exc:
            self._message.value = str(exc)
        except Exception as exc:  # noqa: BLE001 - a GUI click never kills anything
            log.exception("viewer command failed")
            self._message.value = f"{type(exc).__name__}: {exc}"

    def _update_gui(self, snap) -> None:
        t = f"{snap.time_s:.3f}"
        if self._time.value != t:
            self._time.value = t
        hard = bool(snap.emergency.get("hard_stop", False))
        if self._hard_stop.value != hard:
            self._hard_stop.value = hard
        if self._fallen.value != bool(snap.fallen):
            self._fallen.value = bool(snap.fallen)
        fault = snap.fault or "none"
        if self._fault.value != fault:
            self._fault.value = fault

    # ---- background update ----------------------------------------------------------------------
    def _run(self) -> None:
        period = 1.0 / self.rate_hz
        last_tick, n = -1, 0
        while not self._stop.wait(period):
            try:
                model = self.runtime.loop.plant.model
                if model is not self._model:
                    self._model = model
                    if tuple(model.body(b).name for b in range(model.nbody)) != self._model_key:
                        self._build_scene()  # the simulation was reset to another scene
                snap = self.runtime.loop.snapshot
                if snap.tick != last_tick:
                    self._apply_poses(snap.truth)
                    last_tick = snap.tick
                n += 1
                if n % max(1, int(self.rate_hz / 5)) == 0:
                    self._update_gui(snap)
            except Exception:  # noqa: BLE001 - keep drawing whatever happens
                log.exception("viewer update failed")
                time.sleep(0.5)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.server.stop()
