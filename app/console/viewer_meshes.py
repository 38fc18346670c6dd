"""MuJoCo geoms as viser scene nodes: a model's bodies as frames holding their visual geoms (boxes, planes as grids,
the rest as triangle meshes), for the live view (app/console/viewer.py) and the replay (app/lab/replay_viewer.py)."""

from __future__ import annotations

import logging

import mujoco
import numpy as np
import trimesh

log = logging.getLogger(__name__)

_VISUAL_GROUPS = (0, 1, 2)  # MJCF geom groups drawn by default; group 3 holds the collision shapes
#: The robot's silhouette (robot/silhouette.py): a body with geoms in this group is drawn by them alone.
_SILHOUETTE_GROUP = 5


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


def drawn_geoms(model: mujoco.MjModel) -> list[int]:
    """The geoms the view draws: a body's silhouette if it has one, else its visual geoms (groups 0-2), else (a
    body with none) its collision geoms."""
    groups = np.asarray(model.geom_group)
    bodies = np.asarray(model.geom_bodyid)
    has_silhouette = np.zeros(model.nbody, dtype=bool)
    has_visual = np.zeros(model.nbody, dtype=bool)
    has_silhouette[bodies[groups == _SILHOUETTE_GROUP]] = True
    has_visual[bodies[np.isin(groups, _VISUAL_GROUPS)]] = True
    out = []
    for g in range(model.ngeom):
        b = bodies[g]
        if has_silhouette[b]:
            keep = groups[g] == _SILHOUETTE_GROUP
        else:
            keep = (groups[g] in _VISUAL_GROUPS) == bool(has_visual[b]) and groups[g] != _SILHOUETTE_GROUP
        if keep:
            out.append(g)
    return out


def add_model(scene, model: mujoco.MjModel) -> tuple[list, list]:
    """Draw a MuJoCo model's bodies in a viser scene: one frame per moving body ("/bodies/<name>", placed later
    from body poses) holding the geoms drawn_geoms() picks, the world's geoms under "/static". Returns (the
    frames of bodies 1..nbody-1, every node made)."""
    names = tuple(model.body(b).name for b in range(model.nbody))
    frames, nodes = [], []
    for b in range(1, model.nbody):
        frame = scene.add_frame(f"/bodies/{names[b]}", show_axes=False)
        frames.append(frame)
        nodes.append(frame)
    for g in drawn_geoms(model):
        b = model.geom_bodyid[g]
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
