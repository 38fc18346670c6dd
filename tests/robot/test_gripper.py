"""The JRL-hand gripper holds the operation paper's 85 mm can against gravity within its 14 N grip limit."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import robot.generate as gen
from robot.names import JOINT_NAMES, MJCF_SCENE

CAN_RADIUS_M = 0.0425
CAN_HEIGHT_M = 0.12
CAN_MASS_KG = 0.35
GRIP_LIMIT_N = 14.0
#: Allowance for the dynamic transient of the jaw closing on the can [N].
TRANSIENT_TOLERANCE_N = 1.0


def fixed_base_scene_with_can() -> tuple[mujoco.MjModel, int]:
    """The robot with BODY fixed to the world (no freejoint) and a free 85 mm can."""
    spec = mujoco.MjSpec.from_file(str(MJCF_SCENE))
    spec.delete(spec.joint("root"))
    for key in list(spec.keys):
        spec.delete(key)
    can = spec.worldbody.add_body(name="can")
    can.add_freejoint(name="can_free")
    can.mass = CAN_MASS_KG
    side_inertia = CAN_MASS_KG * (3 * CAN_RADIUS_M**2 + CAN_HEIGHT_M**2) / 12
    can.inertia = [side_inertia, side_inertia, CAN_MASS_KG * CAN_RADIUS_M**2 / 2]
    can.explicitinertial = True
    can.add_geom(name="can", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[CAN_RADIUS_M, CAN_HEIGHT_M / 2, 0],
                 friction=[1.0, 0.005, 0.0001])
    model = spec.compile()
    return model, model.geom("can").id


def arm_pose_rad(gripper_rad: float) -> np.ndarray:
    """Right forearm forward, wrist turned so the hand's y axis (the can's axis) is vertical."""
    q = np.zeros(len(JOINT_NAMES))
    q[JOINT_NAMES.index("RARM_JOINT3")] = -math.pi / 2
    q[JOINT_NAMES.index("RARM_JOINT4")] = math.pi / 2
    q[JOINT_NAMES.index("RARM_JOINT6")] = gripper_rad
    return q


def normal_forces_on_can(model, data, can_geom: int) -> dict[str, float]:
    """Sum of contact normal forces on the can per touching geom [N]."""
    out: dict[str, float] = {}
    wrench = np.zeros(6)
    for i in range(data.ncon):
        contact = data.contact[i]
        if can_geom in contact.geom:
            other = contact.geom[1] if contact.geom[0] == can_geom else contact.geom[0]
            mujoco.mj_contactForce(model, data, i, wrench)
            out[model.geom(other).name] = out.get(model.geom(other).name, 0.0) + wrench[0]
    return out


@pytest.fixture(scope="module")
def grasp():
    model, can_geom = fixed_base_scene_with_can()
    data = mujoco.MjData(model)
    open_rad = model.jnt_range[model.joint("RARM_JOINT6").id][0]
    close_rad = model.jnt_range[model.joint("RARM_JOINT6").id][1]
    q = arm_pose_rad(open_rad)
    data.qpos[[model.joint(n).qposadr[0] for n in JOINT_NAMES]] = q
    data.ctrl[:] = q
    mujoco.mj_forward(model, data)
    # the can between the open jaws, against the fixed jaw, its axis along the hand's y axis
    centre_in_hand, _ = gen.grasp_centre(gen.load_parameters(), "RARM")
    R_world_hand = data.body("RARM_LINK5").xmat.reshape(3, 3)
    can_adr = model.joint("can_free").qposadr[0]
    data.qpos[can_adr:can_adr + 3] = data.body("RARM_LINK5").xpos + R_world_hand @ np.array(centre_in_hand)
    R_world_can = np.column_stack([R_world_hand[:, 0], -R_world_hand[:, 2], R_world_hand[:, 1]])
    mujoco.mju_mat2Quat(data.qpos[can_adr + 3:can_adr + 7], R_world_can.flatten())
    # close without gravity (the can is "handed over"), then let gravity act for 2 s
    gravity = model.opt.gravity.copy()
    model.opt.gravity[:] = 0.0
    data.ctrl[JOINT_NAMES.index("RARM_JOINT6")] = close_rad
    mujoco.mj_step(model, data, 500)
    model.opt.gravity[:] = gravity
    z_start_m = data.qpos[can_adr + 2]
    pad_forces_n = []
    for _ in range(2000):
        mujoco.mj_step(model, data)
        pad_forces_n.append(normal_forces_on_can(model, data, can_geom).get("rarm_finger_pad", 0.0))
    return {"model": model, "data": data, "z_start_m": z_start_m, "can_adr": can_adr,
            "pad_forces_n": np.array(pad_forces_n), "can_geom": can_geom, "R_world_hand": R_world_hand}


def test_hand_axis_is_vertical_so_gravity_pulls_along_the_can(grasp):
    assert abs(grasp["R_world_hand"][2, 1]) > 0.999


def test_gripper_opens_wider_than_the_can():
    params = gen.load_parameters()
    face_x = gen.gripper_fixed_jaw_face_x(params, "RARM")
    px, _, _ = gen.gripper_pivot(params, "RARM")
    open_rad = math.radians(-60.0)
    pad_inner_x = px + gen.FINGER_PAD_DEPTH_M * math.sin(-open_rad) - gen.FINGER_PAD_RADIUS_M
    assert pad_inner_x - face_x > 2 * CAN_RADIUS_M


def test_can_stays_held_for_two_seconds_against_gravity(grasp):
    data, adr = grasp["data"], grasp["can_adr"]
    drop_m = grasp["z_start_m"] - data.qpos[adr + 2]
    assert drop_m < 0.005
    touching = normal_forces_on_can(grasp["model"], data, grasp["can_geom"])
    assert touching.get("rarm_finger_pad", 0.0) > 1.0 and touching.get("rarm_fixed_jaw", 0.0) > 1.0


def test_jaw_normal_force_is_within_the_14_newton_grip_limit(grasp):
    forces_n = grasp["pad_forces_n"]
    assert forces_n.max() <= GRIP_LIMIT_N + TRANSIENT_TOLERANCE_N
    assert forces_n[-1] > 0.5 * GRIP_LIMIT_N  # it really squeezes
