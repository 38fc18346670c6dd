"""Take Can de-risked: the free-standing robot's right hand grips the 65 mm can by friction, lifts and carries it.

A check of the grasp contact model (robot/hrp2/README.md, "Contact model for grasping"), not of a behaviour:
no controller chain, the arm's joint targets planned once with the controller's limb IK from the BODY pose
the simulator reports after settling, and played on the servos every 5 ms.

1. The table is placed close to the robot, the can 0.15 m in from its edge on the right shoulder's line.
2. The open hand comes up in front of the table edge, forward to the pre-grasp, and onto the can.
3. The finger closes (torque limited: 14 N at the fingertip); the hand lifts 8 cm.
4. The hand carries the can toward the body, sideways and back, 1 s per leg; slip is the can's pose in the hand.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import robot.generate as gen
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import matrix_to_rpy, quat_wxyz_to_matrix
from robot.names import JOINT_GROUPS, JOINT_NAMES
from robot.plant import MujocoPlant

pytestmark = pytest.mark.slow

TICK_STEPS = 5  # servo targets written every 5 ms, as the controller does
#: The table is moved to the robot (near edge 0.25 m ahead of BODY, clear of the knees and the torso, which
#: overhangs the 0.70 m table top by 1 cm); the can 0.15 m in from the edge, on the right shoulder's line.
TABLE_NEAR_EDGE_X_M = 0.25
CAN_XY_M = (TABLE_NEAR_EDGE_X_M + 0.15, -0.25)
#: The hand reaches forward and 30 deg down, the jaws closing along world y around the upright can (with a
#: level hand the forearm would have to be horizontal at can height, 0.42 m below the shoulder: out of reach).
HAND_PITCH_DEG = 30.0
GRASP_ABOVE_CENTRE_M = 0.015  # grip 1.5 cm above the can's middle: the jaw tips clear the table top
PRE_GRASP_BACK_M = 0.10
LIFT_M = 0.08
#: After the lift, the hand carries the can toward the body and up, sideways, back: 1 s each, stopping at each.
CARRY_OFFSETS_M = ((-0.10, 0.0, 0.05), (-0.10, -0.05, 0.05), (0.0, -0.05, 0.0), (0.0, 0.0, 0.0))
OPEN_RAD, CLOSED_RAD = math.radians(-60.0), math.radians(16.0)
GRIP_LIMIT_N = 14.0
GRIP_TORQUE_LIMIT_NM = GRIP_LIMIT_N * gen.FINGER_PAD_DEPTH_M
#: The servo is torque limited: 14 N at the 0.085 m fingertip = 1.19 N m. Measured: the pad presses 15.4-15.7 N
#: while lifted, because it meets the tilted can 20 deg off the finger's normal (lever 0.079 m), so the same
#: torque presses harder. Allowed: 14 N + 2 N.
PAD_FORCE_TOLERANCE_N = 2.0
#: Measured slip of the can relative to the hand from closing to the end: 1.0 mm, 0.5 deg. Required < 5 mm.
SLIP_LIMIT_M = 0.005
SLIP_ROTATION_LIMIT_DEG = 3.0
APPROACH_PUSH_LIMIT_M = 0.005
#: Measured: BODY tilts 0.3 deg at most on its servos alone; allowed 1 deg.
TILT_LIMIT_DEG = 1.0


def smooth(s: float) -> float:
    """Minimum-jerk time scaling on [0, 1]."""
    return s ** 3 * (10 - 15 * s + 6 * s * s)


class GraspRun:
    """Plan the grasp with pinocchio (controller.kinematics) and play it on the plant's servos, recording."""

    def __init__(self) -> None:
        self.plant = plant = MujocoPlant("expo")
        plant.place_object("table", (TABLE_NEAR_EDGE_X_M + gen.EXPO_TABLE_SIZE_M[0] / 2, 0.0))
        self.can_start_m = plant.place_object("can", CAN_XY_M)
        self.q_home = np.array(plant.data.ctrl)
        self.arm = list(JOINT_GROUPS["rarm"])
        self.grip = JOINT_NAMES.index("RARM_JOINT6")
        self.log: dict[str, list] = {"slip_m": [], "slip_deg": [], "pad_n": [], "grip_nm": [], "tilt_deg": []}
        self.table_touches: set[str] = set()
        self.ref = None
        self._hold(0.5, self.q_home)
        truth = plant.ground_truth()
        self.base_pos = truth.base_pos_world.copy()
        self.base_rpy = matrix_to_rpy(quat_wxyz_to_matrix(truth.base_quat_wxyz))
        self.kin = RobotKinematics()
        params = gen.load_parameters()
        centre_85, _ = gen.grasp_centre(params, "RARM")  # where rarm_end is
        centre_65, self.finger_at_grasp_rad = gen.grasp_centre(params, "RARM", gen.CAN_DIAMETER_M / 2)
        self.can_to_site_in_hand = np.array(centre_85) - np.array(centre_65)
        a = math.radians(HAND_PITCH_DEG)
        self.approach = np.array([math.cos(a), 0.0, -math.sin(a)])
        z_hand = -self.approach  # the fingers point along the hand's -z
        x_hand = np.array([0.0, 1.0, 0.0])  # jaws close along the hand's x
        self.R_world_hand = np.column_stack([x_hand, np.cross(z_hand, x_hand), z_hand])

    # -------------------------------------------------------------- planning

    def ik(self, can_centre_m, q_seed) -> np.ndarray:
        """Joint targets putting the 65 mm grasp centre at can_centre_m with the grasp orientation."""
        site = can_centre_m + self.R_world_hand @ self.can_to_site_in_hand
        return self.kin.limb_ik("rarm", q_seed, self.base_pos, self.base_rpy, site, self.R_world_hand, max_iter=200)

    def line(self, start_m, end_m, q_start, n: int = 15) -> list[np.ndarray]:
        qs = [q_start]
        for s in np.linspace(0.0, 1.0, n)[1:]:
            qs.append(self.ik(start_m + s * (end_m - start_m), qs[-1]))
        return qs

    # -------------------------------------------------------------- playing

    def _tick(self, q) -> None:
        plant = self.plant
        plant.write(q)
        plant.step(TICK_STEPS)
        m, d = plant.model, plant.data
        for c in d.contact[:d.ncon]:
            names = {m.geom(c.geom1).name, m.geom(c.geom2).name}
            if "table_top" in names and "can" not in names:
                self.table_touches |= names - {"table_top"}
        w, x, y, _ = d.body("BODY").xquat
        self.log["tilt_deg"].append(math.degrees(math.acos(min(1.0, 1 - 2 * (x * x + y * y)))))
        if self.ref is not None:
            p, R = self.can_in_hand()
            self.log["slip_m"].append(float(np.linalg.norm(p - self.ref[0])))
            cos = (np.trace(self.ref[1].T @ R) - 1) / 2
            self.log["slip_deg"].append(math.degrees(math.acos(max(-1.0, min(1.0, cos)))))
            self.log["pad_n"].append(self.pad_force_n())
            self.log["grip_nm"].append(abs(float(d.actuator_force[m.actuator("RARM_JOINT6").id])))

    def _hold(self, duration_s: float, q) -> None:
        for _ in range(round(duration_s / (TICK_STEPS * self.plant.dt_physics))):
            self._tick(q)

    def _play(self, duration_s: float, path, grip_rad: float) -> np.ndarray:
        path = np.array(path)
        path[:, self.grip] = grip_rad
        n = len(path) - 1
        ticks = round(duration_s / (TICK_STEPS * self.plant.dt_physics))
        for k in range(ticks):
            s = smooth((k + 1) / ticks) * n
            i = min(int(s), n - 1)
            self._tick(path[i] + (s - i) * (path[i + 1] - path[i]))
        return path[-1]

    def can_in_hand(self) -> tuple[np.ndarray, np.ndarray]:
        d = self.plant.data
        R_hand = d.body("RARM_LINK5").xmat.reshape(3, 3)
        p = R_hand.T @ (d.body("can").xpos - d.body("RARM_LINK5").xpos)
        return p, R_hand.T @ d.body("can").xmat.reshape(3, 3)

    def pad_force_n(self) -> float:
        m, d = self.plant.model, self.plant.data
        pad, can = m.geom("rarm_finger_pad").id, m.geom("can").id
        total, wrench = 0.0, np.zeros(6)
        for i in range(d.ncon):
            if {d.contact[i].geom1, d.contact[i].geom2} == {pad, can}:
                mujoco.mj_contactForce(m, d, i, wrench)
                total += wrench[0]
        return total

    def touching_can(self) -> set[str]:
        m, d = self.plant.model, self.plant.data
        can = m.geom("can").id
        return {m.geom(int(g)).name for c in d.contact[:d.ncon] if can in (c.geom1, c.geom2)
                for g in (c.geom1, c.geom2) if g != can}

    def run(self) -> GraspRun:
        grasp = self.can_start_m + np.array([0.0, 0.0, GRASP_ABOVE_CENTRE_M])
        pre = grasp - PRE_GRASP_BACK_M * self.approach
        via = pre + np.array([-0.10, 0.0, 0.02])  # the hand comes up in front of the table edge first
        seed = self.q_home.copy()
        seed[self.arm[:6]] = np.radians([0.0, -30.0, 30.0, -75.0, 50.0, 20.0])
        q_grasp = self.ik(grasp, seed)
        q_pre = self.ik(pre, q_grasp)
        q_via = self.ik(via, q_pre)
        q = self._play(2.0, [self.q_home, q_via], OPEN_RAD)
        q = self._play(1.0, self.line(via, pre, q), OPEN_RAD)
        q = self._play(1.5, self.line(pre, grasp, q), OPEN_RAD)
        self.touching_before_close = self.touching_can()
        self.can_before_close_m = self.plant.object_pose("can")[0].copy()
        closing = q.copy()
        closing[self.grip] = CLOSED_RAD
        self._hold(1.0, closing)
        m, d = self.plant.model, self.plant.data
        self.finger_closed_rad = float(d.qpos[m.joint("RARM_JOINT6").qposadr[0]])
        self.touching_closed = self.touching_can()
        self.ref = self.can_in_hand()
        lift = grasp + np.array([0.0, 0.0, LIFT_M])
        q = self._play(1.5, self.line(grasp, lift, q), CLOSED_RAD)
        self.can_lifted_m = self.plant.object_pose("can")[0].copy()
        self.touching_lifted = self.touching_can()
        start = lift
        for offset in CARRY_OFFSETS_M:
            end = lift + np.array(offset)
            q = self._play(1.0, self.line(start, end, q), CLOSED_RAD)
            start = end
        self._hold(1.0, q)
        return self


@pytest.fixture(scope="module")
def grasp() -> GraspRun:
    return GraspRun().run()


def test_the_can_is_held_by_contact_alone():
    model = MujocoPlant("expo").model
    assert model.neq == 0  # no weld, no connect, no equality of any kind
    assert model.jnt_type[model.joint("can_free").id] == mujoco.mjtJoint.mjJNT_FREE


def test_the_hand_reaches_around_the_can_without_touching_the_table(grasp):
    assert grasp.table_touches == set()
    assert "rarm_finger_pad" not in grasp.touching_before_close  # open: the finger is clear of the can
    # the fixed jaw arrives against the can's side; measured: it nudged the can 0.95 mm; allowed 5 mm
    assert np.linalg.norm(grasp.can_before_close_m - grasp.can_start_m) < APPROACH_PUSH_LIMIT_M


def test_the_gripper_closes_on_the_can_with_both_jaws_far_from_its_limit(grasp):
    assert {"rarm_finger_pad", "rarm_fixed_jaw"} <= grasp.touching_closed
    assert grasp.finger_closed_rad == pytest.approx(grasp.finger_at_grasp_rad, abs=math.radians(5.0))
    assert grasp.finger_closed_rad < CLOSED_RAD - math.radians(30.0)


def test_the_grip_stays_within_the_14_newton_fingertip_limit(grasp):
    assert max(grasp.log["grip_nm"]) <= GRIP_TORQUE_LIMIT_NM + 1e-9  # the servo's force range
    pad_n = np.array(grasp.log["pad_n"])
    assert pad_n.max() <= GRIP_LIMIT_N + PAD_FORCE_TOLERANCE_N
    assert pad_n.min() > 0.8 * GRIP_LIMIT_N  # it squeezes all the time


def test_the_can_is_lifted_8_cm_off_the_table_by_the_hand(grasp):
    lifted_m = grasp.can_lifted_m[2] - grasp.can_start_m[2]
    assert 0.05 <= lifted_m <= 0.10
    assert lifted_m == pytest.approx(LIFT_M, abs=0.01)
    assert "table_top" not in grasp.touching_lifted


def test_the_can_slips_less_than_5_mm_in_the_hand_while_lifted_and_carried(grasp):
    assert max(grasp.log["slip_m"]) < SLIP_LIMIT_M, f"slip {max(grasp.log['slip_m']) * 1e3:.2f} mm"
    assert max(grasp.log["slip_deg"]) < SLIP_ROTATION_LIMIT_DEG
    assert {"rarm_finger_pad", "rarm_fixed_jaw"} <= grasp.touching_can()  # still held at the end


def test_the_robot_stands_on_its_servos_throughout_without_warnings(grasp):
    assert max(grasp.log["tilt_deg"]) < TILT_LIMIT_DEG
    assert grasp.plant.warnings() == {}
