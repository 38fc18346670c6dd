"""The fridge's handle located in rendered head-camera images, the hinge found from it, and the door's arc
(follow_arc's twists stay on the hinge's circle)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from behaviors.follow_arc import arc_point, arc_twist
from behaviors.perception.locate_fridge import FRIDGE, door_yaw_rad, hinge_from_handle_xy, locate_fridge_handle
from robot import scene_fridge as sf
from robot.camera import CameraRig
from robot.plant import MujocoPlant


def test_the_robots_fridge_model_matches_the_scene():
    assert FRIDGE.handle_radius_m == sf.FRIDGE_HANDLE_RADIUS_M
    assert FRIDGE.handle_from_hinge_m == sf.FRIDGE_HANDLE_FROM_HINGE_M
    assert FRIDGE.handle_off_door_m == pytest.approx(sf.FRIDGE_DOOR_THICKNESS_M + sf.FRIDGE_HANDLE_STANDOFF_M)
    assert FRIDGE.handle_length_m == pytest.approx(sf.FRIDGE_HANDLE_Z_M[1] - sf.FRIDGE_HANDLE_Z_M[0])


@pytest.mark.parametrize("yaw_deg", [-4.0, 0.0, 4.0])
def test_the_hinge_is_found_back_from_the_handle_and_the_doors_turn(yaw_deg):
    yaw = math.radians(yaw_deg)
    hinge = np.array([0.58, -0.42])
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([-FRIDGE.handle_off_door_m, FRIDGE.handle_from_hinge_m])
    handle = hinge + np.array([c * local[0] - s * local[1], s * local[0] + c * local[1]])
    np.testing.assert_allclose(hinge_from_handle_xy(handle, yaw), hinge, atol=1e-12)


def test_the_door_normal_points_away_from_the_camera_whatever_the_point_order():
    t = np.linspace(0.0, 0.5, 20)
    yaw = math.radians(10.0)
    pts = np.column_stack([0.6 - math.sin(yaw) * t, -0.4 + math.cos(yaw) * t])
    assert math.degrees(door_yaw_rad(pts, (0.0, 0.0))) == pytest.approx(10.0, abs=1e-9)
    assert math.degrees(door_yaw_rad(pts[::-1], (0.0, 0.0))) == pytest.approx(10.0, abs=1e-9)
    with pytest.raises(ValueError, match="at least 3"):
        door_yaw_rad(pts[:2], (0.0, 0.0))


def test_arc_twists_integrated_tick_by_tick_stay_on_the_circle():
    p0, centre, dt = np.array([0.42, -0.2, 0.8]), (0.58, -0.42), 0.005
    p = p0.copy()
    angles = np.linspace(0.0, math.radians(40.0), 801)
    for a0, a1 in zip(angles[:-1], angles[1:], strict=True):
        linear, angular = arc_twist(p0, centre, a0, a1, dt)
        p = p + linear * dt
        assert angular[2] == pytest.approx((a1 - a0) / dt)
    np.testing.assert_allclose(p, arc_point(p0, centre, math.radians(40.0)), atol=1e-12)
    r0 = np.hypot(p0[0] - centre[0], p0[1] - centre[1])
    assert np.hypot(p[0] - centre[0], p[1] - centre[1]) == pytest.approx(r0, abs=1e-12)
    with pytest.raises(ValueError, match="dt_s"):
        arc_twist(p0, centre, 0.0, 0.1, 0.0)


def _rendered_handle(yaw_deg: float, door_deg: float):
    """The fridge turned `yaw_deg` about its hinge and its door open `door_deg`, seen by the narrow camera of the
    standing robot with its head turned right 25 deg and pitched down 40 deg: (recognition from the true camera
    pose, true handle top)."""
    plant = MujocoPlant("fridge")
    m, d = plant.model, plant.data
    mujoco.mj_resetDataKeyframe(m, d, 0)
    yaw = math.radians(yaw_deg)
    d.mocap_quat[0] = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
    d.qpos[m.joint("fridge_door_hinge").qposadr[0]] = math.radians(door_deg)
    d.qpos[m.joint("HEAD_JOINT0").qposadr[0]] = math.radians(-25.0)
    d.qpos[m.joint("HEAD_JOINT1").qposadr[0]] = math.radians(40.0)
    mujoco.mj_forward(m, d)
    with CameraRig("fridge", cameras=("narrow_left",)) as rig:
        frames = rig.render(d.qpos.copy(), 0.0, d.mocap_pos.copy(), d.mocap_quat.copy())
    image = frames["narrow_left"]
    r = locate_fridge_handle(image.rgb, image.depth_m, image.intrinsics, frames.T_world_camera_true["narrow_left"])
    g = m.geom("fridge_handle").id
    ends = [d.geom_xpos[g] + k * d.geom_xmat[g].reshape(3, 3)[:, 2] * m.geom_size[g][1] for k in (-1.0, 1.0)]
    top = max(ends, key=lambda e: e[2])
    return r, top


@pytest.mark.parametrize(("yaw_deg", "door_deg"), [(0.0, 0.0), (-4.0, 0.0), (4.0, 0.0), (0.0, 10.0)])
def test_the_handle_and_the_doors_turn_are_located_in_a_rendered_image(yaw_deg, door_deg):
    r, top = _rendered_handle(yaw_deg, door_deg)
    assert r is not None
    # measured: 2.3-2.4 mm and < 0.01 deg; 3 mm and 1 deg of margin
    assert np.linalg.norm(r.position_world_m - top) < 0.0055
    assert math.degrees(r.yaw_rad) == pytest.approx(yaw_deg + door_deg, abs=1.0)
