"""Simulator operations on a scene's loose objects: list them, read their true pose, place them (tests, setup)."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from robot.names import BASE_LINK

#: How far above the highest geom a support-finding ray starts [m].
RAY_START_ABOVE_M = 1.0


def placeable_objects(model: mujoco.MjModel) -> dict[str, str]:
    """Bodies a simulator operation may move: name -> "free" (a free joint, moves under physics) or "fixed"
    (a mocap body: static for the physics, moved only by place_object). The robot is not one of them."""
    robot_root = model.body(BASE_LINK).id
    out: dict[str, str] = {}
    for b in range(1, model.nbody):
        if model.body_rootid[b] == robot_root:
            continue
        if model.body_mocapid[b] >= 0:
            out[model.body(b).name] = "fixed"
        elif model.body_jntnum[b] == 1 and model.jnt_type[model.body_jntadr[b]] == mujoco.mjtJoint.mjJNT_FREE:
            out[model.body(b).name] = "free"
    return out


def _object_id(model: mujoco.MjModel, name: str) -> tuple[int, str]:
    objects = placeable_objects(model)
    if name not in objects:
        valid = ", ".join(objects) or "(none in this scene)"
        raise ValueError(f"unknown object {name!r}; valid objects: {valid}")
    return model.body(name).id, objects[name]


def _yaw_quat(yaw_rad: float) -> np.ndarray:
    return np.array([math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)])


def lowest_point_in_body_m(model: mujoco.MjModel, body_id: int) -> float:
    """z of the lowest point of a body's geoms in the body frame [m] (from each geom's bounding box)."""
    lowest = math.inf
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    for g in range(model.ngeom):
        if model.geom_bodyid[g] != body_id:
            continue
        centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, model.geom_quat[g])
        corners = (centre + signs * half) @ R.reshape(3, 3).T + model.geom_pos[g]
        lowest = min(lowest, float(corners[:, 2].min()))
    if not math.isfinite(lowest):
        raise ValueError(f"body {model.body(body_id).name!r} has no geoms to rest on")
    return lowest


def support_height_m(model: mujoco.MjModel, data: mujoco.MjData, xy, exclude_body: int) -> float:
    """Height of the highest surface below (x, y) [m], ignoring the robot and `exclude_body`; 0 if none."""
    robot_root = model.body(BASE_LINK).id
    top = float(np.max(data.geom_xpos[:, 2] + model.geom_rbound)) if model.ngeom else 0.0
    start = np.array([xy[0], xy[1], max(top, 0.0) + RAY_START_ABOVE_M])
    down = np.array([0.0, 0.0, -1.0])
    geom_id = np.zeros(1, dtype=np.int32)
    while True:
        distance = mujoco.mj_ray(model, data, start, down, None, 1, exclude_body, geom_id)
        if distance < 0:
            return 0.0
        hit = start + distance * down
        if model.body_rootid[model.geom_bodyid[geom_id[0]]] != robot_root:
            return float(hit[2])
        start = hit + 1e-6 * down  # through the robot's geom


def place_object(model: mujoco.MjModel, data: mujoco.MjData, name: str, position, yaw_rad: float = 0.0
                 ) -> np.ndarray:
    """Put an object at `position` with yaw `yaw_rad` about the world z axis, at rest; return its body position.

    `position`: (x, y, z) of the body origin [m, world], or (x, y): standing upright on what is below, a free
    object on the highest surface below (x, y) that is not the robot (table, lid, box bottom, floor), a fixed
    one on the floor. Free objects get zero velocity; then kinematics and contacts are recomputed (mj_forward).
    """
    body_id, kind = _object_id(model, name)
    try:
        pos = np.asarray(position, dtype=float)
    except (TypeError, ValueError):
        pos = np.full(1, np.nan)
    if pos.shape not in ((2,), (3,)) or not np.all(np.isfinite(pos)):
        raise ValueError(f"position must be (x, y) or (x, y, z) finite [m], got {position!r}")
    if not math.isfinite(yaw_rad):
        raise ValueError(f"yaw_rad must be finite, got {yaw_rad!r}")
    if pos.shape == (2,):
        mujoco.mj_kinematics(model, data)
        support = support_height_m(model, data, pos, body_id) if kind == "free" else 0.0
        pos = np.array([pos[0], pos[1], support - lowest_point_in_body_m(model, body_id)])
    quat = _yaw_quat(yaw_rad)
    if kind == "fixed":
        mocap = model.body_mocapid[body_id]
        data.mocap_pos[mocap] = pos
        data.mocap_quat[mocap] = quat
    else:
        joint = model.body_jntadr[body_id]
        qadr, vadr = model.jnt_qposadr[joint], model.jnt_dofadr[joint]
        data.qpos[qadr:qadr + 3] = pos
        data.qpos[qadr + 3:qadr + 7] = quat
        data.qvel[vadr:vadr + 6] = 0.0
    mujoco.mj_forward(model, data)
    return pos.copy()


def object_pose(model: mujoco.MjModel, data: mujoco.MjData, name: str) -> tuple[np.ndarray, np.ndarray]:
    """The true pose of an object: (position (3,) [m, world], quaternion wxyz (4,)), after the last forward pass."""
    body_id, _ = _object_id(model, name)
    return data.xpos[body_id].copy(), data.xquat[body_id].copy()
