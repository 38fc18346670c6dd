"""The [MLC] wall scene through the operation layer ([OP] V, issue 10 "Done when"): the operator drives the
right hand by velocity (op.set_motion) into the front wall. With the EmergencyStopper the Stabilizer's
capture-point flag stops and reverts the operator's motion and the robot stands; the operator's stream
after the flag does not re-push the hand, and after the release the hand does not go back into the wall.
Without it the robot falls.

The hand is measured from the encoders (FK with the KalmanFilter attitude, relative to the soles), the
tilt from the simulator's ground truth (test only)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.lab.experiments.wall import REACH_FORWARD_DEG
from controller.operation.points import Twist
from robot.names import JOINT_NAMES
from tests.scenarios.helpers import tilt_deg
from tests.scenarios.test_operation_teleop import DT, Teleop

pytestmark = pytest.mark.slow
FORWARD = Twist.of((0.1, 0.0, 0.0))  # into the wall, 0.1 m/s
# the right hand starts at REACH_FORWARD_DEG (its jaws 0.05 m before the wall face)


def at_the_wall(with_stopper: bool) -> Teleop:
    """Standing in the wall scene, the right arm brought to REACH_FORWARD_DEG by the SequencePlayer."""
    robot = Teleop("wall")
    loop = robot.loop
    loop.chain["es"].enabled = with_stopper
    q = np.array(loop.snapshot.q_seq_rad)
    for name, deg in REACH_FORWARD_DEG.items():
        if name.startswith("RARM"):
            q[JOINT_NAMES.index(name)] = math.radians(deg)
    loop.call(lambda: loop.chain["seq"].set_joint_angles(q, 2.0))
    robot.run(3.0)
    return robot


def step(robot: Teleop, twist: Twist | None):
    """One tick, the operator's setpoint (if any) streamed first; returns (snapshot, tilt [deg])."""
    loop = robot.loop
    if twist is not None:
        robot.op.set_motion("rhand", twist, loop.plant.time_s)
    robot.snap = loop.step()
    return robot.snap, tilt_deg(loop.plant.ground_truth().base_quat_wxyz)


def test_with_the_emergency_stopper_the_flag_stops_the_operator_push_and_release_keeps_the_hand_off_the_wall():
    robot = at_the_wall(with_stopper=True)
    op = robot.op
    # 0. the operator first lowers the hand 5 cm (1 s): the point is operated well before the push, so the
    #    revert (T1 = 1 s) lands on a target op held, which it re-seeds from on release
    for _ in range(round(1.0 / DT)):
        step(robot, Twist.of((0.0, 0.0, -0.05)))
    step(robot, Twist.of())
    robot.run(0.5)
    x0 = robot.measured("rarm_end")[0][0]
    target_before = op.status().to_dict()["points"]["rhand"]["target"]
    # 1. the operator pushes until the capture-point flag stops the motion (measured: after 0.94 s, the
    #    hand 0.077 m on, ~0.03 m pressed into the wall)
    for _ in range(round(4.0 / DT)):
        snap, _ = step(robot, FORWARD)
        if snap.layers["es"].stopped:
            break
    assert snap.layers["es"].stopped and snap.layers["es"].reason == "capture_point"
    step(robot, FORWARD)  # op reads the stop from the ports of the tick before
    assert op.status().motion_stopped
    target_at_flag = op.status().to_dict()["points"]["rhand"]["target"]
    # 2. the operator keeps pushing 3 s: op integrates nothing, the revert takes the hand back off the wall
    worst = 0.0
    for _ in range(round(3.0 / DT)):
        snap, tilt = step(robot, FORWARD)
        worst = max(worst, tilt)
        assert snap.safety.fall is None
    assert op.status().to_dict()["points"]["rhand"]["target"] == target_at_flag
    assert op.status().to_dict()["points"]["rhand"]["limited"] == "motion_stop"
    x_held = robot.measured("rarm_end")[0][0]
    assert x_held - x0 < 0.01  # reverted T1 = 1 s back: to before the push (measured -0.001 m)
    assert worst < 5.0  # measured 1.98 deg at the flag, bound 5; the robot stands
    # 3. the stick let go, the motion released: the hand stays where the revert put it, off the wall
    step(robot, Twist.of())
    robot.loop.call(lambda: robot.loop.chain["es"].release_motion())
    xs = []
    for _ in range(round(3.0 / DT)):
        snap, tilt = step(robot, None)
        xs.append(robot.measured("rarm_end")[0][0])
        assert snap.safety.fall is None and tilt < 5.0  # measured 0.19 deg
    # the revert went back to before the push began (T1 = 1 s > the push until the flag): op restarted from
    # the target it held then, not from the pushed one
    target = op.status().to_dict()["points"]["rhand"]["target"]
    assert np.allclose(target, target_before, atol=1e-3), (target, target_before)
    assert max(xs) - x0 < 0.01  # measured -0.001 m, bound 0.01: never back toward the wall (contact at +0.05 m)


def test_without_the_emergency_stopper_the_same_push_topples_the_robot():
    robot = at_the_wall(with_stopper=False)
    fell_at = None
    for _ in range(round(5.0 / DT)):
        snap, _ = step(robot, FORWARD)
        if snap.safety.fall is not None:
            fell_at = snap.time_s
            break
    # measured: the fall detector fires 2.9 s into the push (the flag rose after 0.94 s with it)
    assert fell_at is not None
