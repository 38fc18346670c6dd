"""The Fig. 8 scenes' objects behave as their modules say: the chair slides when pushed at its rail below the
tipping force and tips above it; the trash stands on the floor and passes through the box's hole."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from robot import scene_objects
from robot.plant import SCENES
from robot.scene_chair import CHAIR_RAIL_HEIGHT_M, rail_x_in_chair_m

FAR_M = (3.0, 2.0)  # [m] away from the robot (which is not controlled here)


def _tilt_deg(quat) -> float:
    return math.degrees(2.0 * math.asin(min(1.0, math.hypot(quat[1], quat[2]))))


def _pushed_chair(force_n: float, seconds: float = 1.0):
    m = mujoco.MjModel.from_xml_path(str(SCENES["chair"]))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    start = scene_objects.place_object(m, d, "chair", FAR_M)
    body = m.body("chair").id
    for _ in range(int(0.3 / m.opt.timestep)):  # settle on its legs
        mujoco.mj_step(m, d)
    rail = d.xpos[body] + np.array([rail_x_in_chair_m(), 0.0, CHAIR_RAIL_HEIGHT_M])
    for _ in range(int(seconds / m.opt.timestep)):
        d.xfrc_applied[body] = 0.0
        mujoco.mj_applyFT(m, d, np.array([force_n, 0.0, 0.0]), np.zeros(3), rail, body, d.qfrc_applied)
        mujoco.mj_step(m, d)
        d.qfrc_applied[:] = 0.0
    pos, quat = scene_objects.object_pose(m, d, "chair")
    return pos - start, _tilt_deg(quat)


def test_the_chair_slides_upright_when_pushed_at_its_rail_between_friction_and_tipping():
    moved, tilt = _pushed_chair(12.0)  # slides at 9.8 N, tips at 13.5 N (robot/scene_chair.py)
    assert moved[0] > 0.05 and tilt < 2.0


def test_the_chair_holds_below_its_friction_and_tips_above_its_tipping_force():
    still, _ = _pushed_chair(8.0)
    assert abs(still[0]) < 0.005
    _, tilt = _pushed_chair(20.0, seconds=0.5)
    assert tilt > 10.0


def test_the_trash_stands_on_the_floor_and_fits_the_hole():
    m = mujoco.MjModel.from_xml_path(str(SCENES["trash"]))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    scene_objects.place_object(m, d, "trash", FAR_M, yaw_rad=0.7)
    for _ in range(int(1.0 / m.opt.timestep)):
        mujoco.mj_step(m, d)
    _, quat = scene_objects.object_pose(m, d, "trash")
    assert _tilt_deg(quat) < 3.0
    body = m.body("trash").id
    geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == body]
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], dtype=float)
    corners = np.vstack([d.geom_xpos[g] + (m.geom_aabb[g, :3] + signs * m.geom_aabb[g, 3:])
                         @ d.geom_xmat[g].reshape(3, 3).T for g in geoms])  # the parts' bounding boxes
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    assert np.all((hi - lo)[:2] < 0.10)  # the 0.12 m wide hole has room (boxes around the parts: an overestimate)
    assert hi[2] - lo[2] == pytest.approx(0.21, abs=0.03)
