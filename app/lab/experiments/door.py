"""[MLC] IV-C 2, Fig. 12, Fig. 13 (gamma): the left hand grasps the knob of a pull door (scene `door`) and moves
it along the door's arc, ImpedanceController on for that hand.

Variants: `push-plan` is the paper's disturbance, a motion planned for pushing the door applied to this pull
door (the door stop resists and the robot is pushed backward); `pull` is the undisturbed task, the door opens.
The planner works from the recognised door (the DOOR_* constants of the scene); the evaluation reads the
door angle from the simulation, the controller never does.
"""

from __future__ import annotations

import math

import numpy as np

from app.lab.experiments.common import Disturbance, Event, Experiment, Rig, pose_with
from controller.core.errors import InvalidCommand
from controller.kinematics.limb_ik import LimbIkParams, PointAxisTarget, solve_limb_ik
from controller.kinematics.model import RobotKinematics
from robot.generate import DOOR_FACE_X_M, DOOR_HINGE_Y_M, DOOR_KNOB_M
from robot.names import JOINT_GROUPS, joint_index

LIMB = "larm"
GRIPPER = "LARM_JOINT6"
GRIPPER_OPEN_DEG = -60.0
GRIPPER_CLOSED_DEG = 16.0  # the closing limit: the servo squeezes with its force limit (14 N at the pad)
#: Where the knob centre sits in the hand when grasped, relative to larm_end in the LARM_LINK5 frame [m]:
#: 5 mm off the fixed jaw's inner face (x = -0.0085 m) for the 60 mm knob, at the height of the closed pad
#: (z = -0.175 m in LARM_LINK5; larm_end is the 85 mm grasp centre at (0.034, 0, -0.193)).
KNOB_IN_END_M = np.array([-0.0085 + 0.005 + 0.03 - 0.034, 0.0, -0.175 + 0.193])
#: The arm posture [deg] (LARM_JOINT0-5) the grasp solution is drawn toward (elbow out and down).
GRASP_POSTURE_DEG = (-10.0, 60.0, -80.0, -100.0, 60.0, -20.0)
APPROACH_M = 0.08  # the hand backs off this far along its axis before closing in on the knob [m]
#: The plans' door angle [deg] at their end (negative: opened toward the robot).
PULL_DEG = -20.0
PUSH_DEG = 30.0
#: The pushing plan bends the waist forward (CHEST_JOINT1) to reach along the push arc [deg].
PUSH_CHEST_PITCH_DEG = 25.0
ARC_VIA_POINTS = 10


def knob_world(door_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """The knob centre [m] and the knob axis (the door normal, toward the door) of the recognised door opened
    by `door_deg` (hinge axis -z, 0 closed)."""
    a = math.radians(-door_deg)  # about +z
    c, s = math.cos(a), math.sin(a)
    rx, ry = DOOR_KNOB_M[0] - DOOR_FACE_X_M, DOOR_KNOB_M[1] - DOOR_HINGE_Y_M
    centre = np.array([DOOR_FACE_X_M + c * rx - s * ry, DOOR_HINGE_Y_M + s * rx + c * ry, DOOR_KNOB_M[2]])
    return centre, np.array([c, s, 0.0])


#: The grasp's IK: the six arm joints (not the gripper), steps of at most 0.05 rad, the free turn drawn toward
#: GRASP_POSTURE_DEG until the step settles; the knob within 2 mm, the jaws within ~1 deg of across it.
ARM_JOINTS = JOINT_GROUPS[LIMB][:6]
GRASP_IK = LimbIkParams(max_iterations=300, damping=1e-4, max_step_rad=0.05, pos_tol_m=2e-3, rot_tol_rad=0.02,
                        posture_gain=0.02, settle_step_rad=1e-5)


def knob_grasp(kin: RobotKinematics, q_rad: np.ndarray, base_pos_world: np.ndarray, knob_world_m: np.ndarray,
               axis_world: np.ndarray) -> np.ndarray:
    """The posture (30,) [rad] whose left hand holds a knob at `knob_world_m` with axis `axis_world`: the knob
    centre at KNOB_IN_END_M and the jaws closing across the knob (hand x axis perpendicular to its axis); the
    hand's turn about that closing direction is free and taken toward GRASP_POSTURE_DEG. From `q_rad`, BODY
    level at `base_pos_world`; raises InvalidCommand when out of reach."""
    target = PointAxisTarget(knob_world_m, KNOB_IN_END_M, np.array([1.0, 0.0, 0.0]), axis_world)
    sol = solve_limb_ik(kin, ARM_JOINTS, kin.frame_ids[f"{LIMB}_end"], target, q_rad, base_pos_world, np.eye(3),
                        GRASP_IK, posture_rad=np.radians(GRASP_POSTURE_DEG))
    if not sol.reached:
        raise InvalidCommand(f"door: the left hand cannot hold the knob at {np.round(knob_world_m, 3).tolist()} "
                             f"(misses by {sol.pos_error_m * 1e3:.1f} mm)")
    return sol.q_rad


def hand_axis(kin: RobotKinematics) -> np.ndarray:
    """The direction the left hand points in (-z of LARM_LINK5) for the last posture `kin` was updated with."""
    return -kin.frame_pose(f"{LIMB}_end")[1][:, 2]


def with_gripper(q_rad: np.ndarray, deg: float) -> np.ndarray:
    q = np.array(q_rad, dtype=float)
    q[joint_index(GRIPPER)] = math.radians(deg)
    return q


def grasp_posture(rig: Rig, door_deg: float, back_off_m: float, q_rad: np.ndarray) -> np.ndarray:
    """The posture holding the knob of the door at `door_deg`, or `back_off_m` behind it along the hand's axis."""
    kin = rig.kin
    base = np.array(rig.snapshot.reference.base_pos_world)
    knob, axis = knob_world(door_deg)
    q = knob_grasp(kin, q_rad, base, knob, axis)
    if back_off_m > 0.0:
        kin.update_rpy(base, np.zeros(3), q)
        q = knob_grasp(kin, q, base, knob - back_off_m * hand_axis(kin), axis)
    return q


def reach(rig: Rig, back_off_m: float, time_s: float) -> None:
    """setJointAngles to the knob grasp (or `back_off_m` short of it), gripper open."""
    q = pose_with(rig, {GRIPPER: GRIPPER_OPEN_DEG})
    q[np.array(JOINT_GROUPS[LIMB][:6])] = np.radians(GRASP_POSTURE_DEG)
    q = grasp_posture(rig, 0.0, back_off_m, q)
    rig.service.set_joint_angles(with_gripper(q, GRIPPER_OPEN_DEG), time_s)


def move_along_arc(rig: Rig, door_deg: float, time_s: float, chest_pitch_deg: float = 0.0) -> None:
    """The planner's door motion: the hand through ARC_VIA_POINTS knob grasps from the closed door to
    `door_deg` while the waist bends forward to `chest_pitch_deg` (CHEST_JOINT1), played as a joint-angle
    sequence, gripper closed. A plan that leaves the arm's reach ends at its last reachable grasp."""
    q = np.array(rig.snapshot.q_seq_rad, dtype=float)
    chest = joint_index("CHEST_JOINT1")
    chest0 = q[chest]
    goals = []
    for k in range(1, ARC_VIA_POINTS + 1):
        f = k / ARC_VIA_POINTS
        q[chest] = chest0 + f * math.radians(chest_pitch_deg)
        try:
            q = grasp_posture(rig, f * door_deg, 0.0, q)
        except InvalidCommand:
            break
        goals.append(with_gripper(q, GRIPPER_CLOSED_DEG))
    rig.service.set_joint_angles_sequence(goals, [time_s / ARC_VIA_POINTS] * len(goals))


def door_script(rig: Rig, variant: str, disturbance: Disturbance) -> list[Event]:
    """Reach to just short of the knob (2 s), close in on it (1 s), close the gripper (0.6 s), start the
    ImpedanceController of the left hand, then move the hand along the door's arc: `pull` toward PULL_DEG in
    3 s, `push-plan` toward PUSH_DEG (against the door stop)."""
    svc = rig.service
    door_deg, chest_deg = (PULL_DEG, 0.0) if variant == "pull" else (PUSH_DEG, PUSH_CHEST_PITCH_DEG)
    return [
        (0.0, lambda: reach(rig, APPROACH_M, 2.0)),
        (2.2, lambda: reach(rig, 0.0, 1.0)),
        (3.4, lambda: svc.set_some_joint_angles({GRIPPER: math.radians(GRIPPER_CLOSED_DEG)}, 0.6)),
        # the ImpedanceController starts once the gripper is closed on the knob: the hand then yields to the
        # door's reaction, not to the knob's contact while the jaws close
        (4.1, lambda: svc.start_impedance(LIMB)),
        (4.5, lambda: move_along_arc(rig, door_deg, 3.0, chest_deg)),
    ]


def door_angle(rig: Rig) -> dict[str, float]:
    """The door angle [deg] measured in the simulation (0 closed, negative open toward the robot)."""
    plant = rig.plant
    adr = plant.model.sensor("door_angle").adr[0]
    return {"door_angle_deg": math.degrees(float(plant.data.sensordata[adr]))}


EXPERIMENTS: dict[str, Experiment] = {
    "door": Experiment("door", door_script, 10.0, door_script.__doc__, variants=("push-plan", "pull"),
                       outcome=door_angle),
}
