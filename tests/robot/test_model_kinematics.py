"""MuJoCo, pinocchio and placo load the same HRP-2: mass, COM, frames, soles, limits, height, cameras."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pinocchio as pin
import placo
import pytest

import robot.generate as gen
from robot.names import END_EFFECTORS, JOINT_NAMES, MJCF_ROBOT, MJCF_SCENE, URDF

PARAMS = gen.load_parameters()
HALF_SITTING_BASE_Z_M = PARAMS["half_sitting_deg"]["base_height_m"]


@pytest.fixture(scope="module")
def mj():
    model = mujoco.MjModel.from_xml_path(str(MJCF_SCENE))
    return model, mujoco.MjData(model)


@pytest.fixture(scope="module")
def pinocchio_model():
    model = pin.buildModelFromUrdf(str(URDF), pin.JointModelFreeFlyer())
    return model, model.createData()


def test_robot_file_loads_alone():
    assert mujoco.MjModel.from_xml_path(str(MJCF_ROBOT)).nu == len(JOINT_NAMES)


def test_total_mass_is_58_kg_in_mujoco_pinocchio_and_placo(mj, pinocchio_model):
    model, _ = mj
    assert model.body_subtreemass[model.body("BODY").id] == pytest.approx(58.0, abs=0.01)
    assert sum(inertia.mass for inertia in pinocchio_model[0].inertias) == pytest.approx(58.0, abs=0.01)
    assert placo.RobotWrapper(str(URDF)).total_mass() == pytest.approx(58.0, abs=0.01)


def test_placo_sees_the_end_effector_frames():
    robot = placo.RobotWrapper(str(URDF))
    robot.update_kinematics()
    for frame in END_EFFECTORS.values():
        assert np.all(np.isfinite(robot.get_T_world_frame(frame)))


def random_configuration(model, rng) -> np.ndarray:
    """MuJoCo qpos: random base pose, joints uniform within their limits."""
    qpos = np.zeros(model.nq)
    qpos[:3] = rng.uniform(-1.0, 1.0, 3)
    quat = rng.normal(size=4)
    qpos[3:7] = quat / np.linalg.norm(quat)
    for name in JOINT_NAMES:
        joint = model.joint(name)
        qpos[joint.qposadr[0]] = rng.uniform(*model.jnt_range[joint.id])
    return qpos


def mujoco_to_pinocchio(qpos, mj_model, pin_model) -> np.ndarray:
    """Map qpos (wxyz base quaternion, MJCF joint order) to pinocchio q (xyzw, its joint order) by names."""
    q = np.zeros(pin_model.nq)
    q[:3] = qpos[:3]
    q[3:7] = qpos[[4, 5, 6, 3]]
    for name in JOINT_NAMES:
        q[pin_model.idx_qs[pin_model.getJointId(name)]] = qpos[mj_model.joint(name).qposadr[0]]
    return q


def test_com_and_end_effectors_agree_between_mujoco_and_pinocchio(mj, pinocchio_model):
    model, data = mj
    pmodel, pdata = pinocchio_model
    rng = np.random.default_rng(10)
    for _ in range(20):
        qpos = random_configuration(model, rng)
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        q = mujoco_to_pinocchio(qpos, model, pmodel)
        com_pin = pin.centerOfMass(pmodel, pdata, q)
        pin.updateFramePlacements(pmodel, pdata)
        assert np.allclose(data.subtree_com[model.body("BODY").id], com_pin, atol=1e-6)
        for frame in END_EFFECTORS.values():
            pos_pin = pdata.oMf[pmodel.getFrameId(frame)].translation
            assert np.allclose(data.site(frame).xpos, pos_pin, atol=1e-6), frame


def sole_corners_z_m(model, data) -> np.ndarray:
    """World z of the 8 bottom corners of both sole boxes [m]."""
    zs = []
    for name in ("rleg_sole", "lleg_sole"):
        geom = data.geom(name)
        half = model.geom(name).size
        R = geom.xmat.reshape(3, 3)
        for sx in (-1, 1):
            for sy in (-1, 1):
                corner = geom.xpos + R @ (np.array([sx, sy, -1.0]) * half)
                zs.append(corner[2])
    return np.array(zs)


def test_soles_touch_the_floor_in_half_sitting(mj):
    model, data = mj
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_kinematics(model, data)
    assert data.qpos[2] == pytest.approx(HALF_SITTING_BASE_Z_M)
    assert np.all(np.abs(sole_corners_z_m(model, data)) < 1e-3)


def test_home_keyframe_has_no_robot_robot_contacts(mj):
    model, data = mj
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    floor = model.geom("floor").id
    robot_pairs = [c.geom for c in data.contact[:data.ncon] if floor not in c.geom]
    assert robot_pairs == []


def test_joint_limits_equal_the_parameter_table(mj):
    model, _ = mj
    for joint in PARAMS["joints"]:
        limits_rad = model.jnt_range[model.joint(joint["name"]).id]
        assert np.allclose(limits_rad, np.radians(joint["limit_deg"]), atol=1e-9)
        assert model.jnt_limited[model.joint(joint["name"]).id]
        assert np.allclose(model.actuator(joint["name"]).ctrlrange, limits_rad, atol=1e-9)


def test_standing_height_in_zero_pose_is_about_1_54_m(mj):
    model, data = mj
    data.qpos[:] = 0.0
    data.qpos[3] = 1.0
    mujoco.mj_kinematics(model, data)
    lowest_sole_z = sole_corners_z_m(model, data).min()
    head = model.geom("head")
    head_top_z = data.geom("head").xpos[2] + head.size[2]
    assert 1.50 < head_top_z - lowest_sole_z < 1.60


@pytest.mark.parametrize(("camera", "hfov_deg", "vfov_deg"),
                         [("wide", 93.6, 70.8), ("narrow_left", 33.1, 25.0), ("narrow_right", 33.1, 25.0)])
def test_camera_fields_of_view_match_the_operation_paper(mj, camera, hfov_deg, vfov_deg):
    model, _ = mj
    cam = model.camera(camera)
    focal_x, focal_y = model.cam_intrinsic[cam.id][:2]
    width_m, height_m = model.cam_sensorsize[cam.id]
    assert math.degrees(2 * math.atan(width_m / (2 * focal_x))) == pytest.approx(hfov_deg, abs=0.1)
    assert math.degrees(2 * math.atan(height_m / (2 * focal_y))) == pytest.approx(vfov_deg, abs=0.1)
    assert model.body(model.cam_bodyid[cam.id]).name == "HEAD_LINK1"


def test_cameras_look_forward(mj):
    model, data = mj
    data.qpos[:] = 0.0
    data.qpos[3] = 1.0
    mujoco.mj_kinematics(model, data)
    for camera in ("wide", "narrow_left", "narrow_right"):
        view_direction_world = -data.cam(camera).xmat.reshape(3, 3)[:, 2]
        assert np.allclose(view_direction_world, [1.0, 0.0, 0.0], atol=1e-9)


def test_stereo_baseline_is_horizontal(mj):
    model, _ = mj
    baseline = model.camera("narrow_left").pos - model.camera("narrow_right").pos
    assert baseline[1] == pytest.approx(0.144) and abs(baseline[0]) < 1e-12 and abs(baseline[2]) < 1e-12


def test_the_controllers_sole_rectangles_match_the_model_sole_boxes():
    """The Stabilizer's support polygon is the simulated sole, not the mesh outline."""
    from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE

    m = mujoco.MjModel.from_xml_path(str(MJCF_ROBOT))
    for geom, rect in (("rleg_sole", HRP2_RIGHT_SOLE), ("lleg_sole", HRP2_LEFT_SOLE)):
        g = m.geom(geom)
        lo = g.pos[:2] - g.size[:2]
        hi = g.pos[:2] + g.size[:2]
        corners = rect.corners_foot()
        assert np.allclose(corners.min(0), lo, atol=1e-9)
        assert np.allclose(corners.max(0), hi, atol=1e-9)
