"""Teleoperation through the operation layer ([OP] V-A, issue 10 "Done when"): a point driven by velocity
moves the simulated robot's point by the integral, orientation held, COM kept over the feet, no fall.

Measured on the simulated robot: forward kinematics of the encoder angles with the KalmanFilter's attitude,
relative to the midpoint of the soles (which stay put), never the simulator's ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    distance_to_polygon_edge,
    support_polygon,
)
from controller.kinematics.model import RobotKinematics, frame_from_soles_midpoint
from controller.operation.points import Twist
from controller.system import ControllerSystem
from robot.plant import MujocoPlant

pytestmark = pytest.mark.slow
DT = 0.005
FRAMES = {"rhand": "rarm_end", "lhand": "larm_end", "head": "HEAD_LINK1", "waist": "BODY"}


class Teleop:
    """The robot standing (2 s settled), an operator streaming setpoints at every tick boundary."""

    def __init__(self, scene: str = "default") -> None:
        self.system = ControllerSystem(MujocoPlant(scene))
        self.loop = self.system.loop
        self.op = self.loop.chain["op"]
        self.kin = RobotKinematics()
        self.min_margin_m = math.inf
        self.snap = None
        self.run(2.0)

    def measured(self, frame: str):
        """(position [m], rotation) of `frame` relative to the soles' midpoint, from the encoders."""
        s = self.snap
        return frame_from_soles_midpoint(self.kin, s.base_rpy_est_rad, s.q_meas_rad, frame)

    def _margin(self) -> float:
        kin = self.kin
        self.measured("BODY")
        (pr, Rr), (pl, Rl) = kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")
        yaw = lambda R: math.atan2(R[1, 0], R[0, 0])  # noqa: E731
        poly = support_polygon([((pr[0], pr[1], yaw(Rr)), HRP2_RIGHT_SOLE), ((pl[0], pl[1], yaw(Rl)), HRP2_LEFT_SOLE)])
        return distance_to_polygon_edge(kin.com_world()[:2], poly)

    def run(self, seconds: float, point: str | None = None, twist: Twist | None = None) -> None:
        for k in range(round(seconds / DT)):
            if point is not None:
                self.op.set_motion(point, twist, self.loop.plant.time_s)
            self.snap = self.loop.step()
            if k % 10 == 0:
                self.min_margin_m = min(self.min_margin_m, self._margin())
        assert self.snap.safety.fall is None and self.snap.fault is None

    def drive(self, point: str, twist: Twist, seconds: float) -> None:
        """Stream `twist` for `seconds`, then the stick released (a zero setpoint), then 1 s to settle."""
        self.run(seconds, point, twist)
        self.run(DT, point, Twist.of())
        self.run(1.0)


def angle_deg(R0, R1) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, 0.5 * (np.trace(R0.T @ R1) - 1.0)))))


def test_rhand_forward_at_0_1_m_s_for_2_s_moves_the_hand_0_20_m():
    robot = Teleop()
    p0, R0 = robot.measured("rarm_end")
    robot.drive("rhand", Twist.of((0.1, 0.0, 0.0)), 2.0)
    p1, R1 = robot.measured("rarm_end")
    d = p1 - p0
    assert d[0] == pytest.approx(0.20, abs=0.01)  # measured 0.198 m
    assert np.hypot(d[1], d[2]) < 0.01  # measured 0.2 mm
    assert angle_deg(R0, R1) < 2.0  # measured 0.19 deg
    assert robot.min_margin_m >= 0.03  # measured 0.051 m


def test_lhand_sideways_at_0_1_m_s_for_2_s_moves_the_hand_0_20_m():
    """Start pose: the left hand first raised 0.20 m (0.1 m/s for 2 s), where 0.20 m outward is within reach
    with its orientation held; from half-sitting the arm gets 0.16-0.17 m outward before LARM_JOINT2 stops it
    (trading 5-6 deg of orientation for it), 0.14 m inward after 0.15 m forward."""
    robot = Teleop()
    robot.drive("lhand", Twist.of((0.0, 0.0, 0.1)), 2.0)
    p0, R0 = robot.measured("larm_end")
    robot.min_margin_m = math.inf
    robot.drive("lhand", Twist.of((0.0, 0.1, 0.0)), 2.0)
    p1, R1 = robot.measured("larm_end")
    d = p1 - p0
    assert d[1] == pytest.approx(0.20, abs=0.01)  # measured 0.197 m
    assert np.hypot(d[0], d[2]) < 0.01  # measured 0.9 mm
    assert angle_deg(R0, R1) < 2.0  # measured 0.58 deg
    assert robot.min_margin_m >= 0.03  # measured 0.087 m


def test_head_yaw_30_deg():
    robot = Teleop()
    _, R0 = robot.measured("HEAD_LINK1")
    robot.drive("head", Twist.of(angular_rad_s=(0.0, 0.0, math.radians(15.0))), 2.0)
    _, R1 = robot.measured("HEAD_LINK1")
    yaw = math.degrees(math.atan2(R1[1, 0], R1[0, 0]) - math.atan2(R0[1, 0], R0[0, 0]))
    assert yaw == pytest.approx(30.0, abs=1.0)  # measured 30.0 deg
    assert robot.min_margin_m >= 0.03


def test_waist_down_0_10_m_and_back():
    robot = Teleop()
    p0, R0 = robot.measured("BODY")
    robot.drive("waist", Twist.of((0.0, 0.0, -0.05)), 2.0)
    p1, R1 = robot.measured("BODY")
    assert p1[2] - p0[2] == pytest.approx(-0.10, abs=0.01)  # measured -0.1006 m
    assert angle_deg(R0, R1) < 2.0
    robot.drive("waist", Twist.of((0.0, 0.0, 0.05)), 2.0)
    p2, _ = robot.measured("BODY")
    assert p2[2] - p0[2] == pytest.approx(0.0, abs=0.01)
    assert robot.min_margin_m >= 0.03


#: [mm] largest CP error after a stick flicked from rhand forward 0.1 m/s to up 0.05 m/s: measured 15.9 mm with the
#: 0.5 m/s^2 hand acceleration limit (51 mm and a motion stop by the CP flag without one); allowed 25 mm
FLICK_CP_ERROR_MM = 25.0


def test_a_stick_flicked_from_forward_to_up_turns_the_hand_without_raising_the_cp_flag():
    robot = Teleop()
    robot.run(2.0, "rhand", Twist.of((0.1, 0.0, 0.0)))
    before = robot.measured("rarm_end")[0]
    worst = 0.0
    for _ in range(round(1.0 / DT)):
        robot.run(DT, "rhand", Twist.of((0.0, 0.0, 0.05)))
        worst = max(worst, robot.snap.layers["st"].cp_error_norm)
        assert robot.snap.layers["op"].points["rhand"].limited != "motion_stop"
    robot.run(DT, "rhand", Twist.of())
    robot.run(1.0)
    assert not robot.snap.layers["es"].stopped
    assert 1e3 * worst < FLICK_CP_ERROR_MM, f"CP error {1e3 * worst:.1f} mm"
    moved = robot.measured("rarm_end")[0] - before
    # it went on forward while it turned (0.5 * 0.1 m/s * 0.2 s = 10 mm) and then up by about 1 s x 0.05 m/s
    assert 0.035 < moved[2] < 0.06 and 0.0 < moved[0] < 0.02, moved


def test_a_hand_driven_past_its_reach_slows_down_on_the_asked_line_and_comes_back_at_once():
    """The right hand asked 0.5 m forward (0.1 m/s for 5 s) from where it hangs: the arm reaches about 0.38 m.
    The point reports `reach`, its target never runs ahead of the pose the IK achieved (the integrator does not
    wind up), and the hand stays on the asked line (measured 0.7 / 1.1 mm across and up; before the target
    advanced by the share of its step made along the asked direction, the IK's best effort drifted it 20 mm
    across and 48 mm up along the workspace's edge). Driven back, it moves back at once (68 mm in 1 s)."""
    robot = Teleop()
    p0, _ = robot.measured("rarm_end")
    reasons, worst_gap_m = set(), 0.0
    for _ in range(round(5.0 / DT)):
        robot.run(DT, "rhand", Twist.of((0.1, 0.0, 0.0)))
        ps = robot.snap.layers["op"].points["rhand"]
        reasons.add(ps.limited)
        worst_gap_m = max(worst_gap_m, float(np.linalg.norm(np.subtract(ps.target[:3], ps.achieved[:3]))))
    assert robot.snap.layers["op"].points["rhand"].limited == "reach"
    assert reasons <= {None, "reach"}
    p1, _ = robot.measured("rarm_end")
    d = p1 - p0
    assert 0.30 < d[0] < 0.45  # measured 0.380 m of the 0.5 m asked
    assert abs(d[1]) < 0.005 and abs(d[2]) < 0.005  # measured 0.7 mm, 1.1 mm
    assert worst_gap_m < 0.002  # measured 0.9 mm
    for _ in range(round(1.0 / DT)):
        robot.run(DT, "rhand", Twist.of((-0.1, 0.0, 0.0)))
    p2, _ = robot.measured("rarm_end")
    assert p2[0] - p1[0] < -0.05  # measured -0.068 m
    assert robot.min_margin_m >= 0.03 and not robot.snap.layers["es"].stopped  # measured 0.051 m
