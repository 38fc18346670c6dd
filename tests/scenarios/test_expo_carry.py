"""Scenario: a can taken by `take_can` stays in the hand through a 1.4 m walk ([OP] VI: the walk to the box).

1. The table is placed with its near edge 0.78 m ahead, the can 0.15 m in on the right shoulder's line.
2. `locate_can`, then `take_can` (it walks the last 0.5 m to its grasping stance, grasps and lifts).
3. `walk_to` turns 90 deg right on the spot (take_can ended 0.5 m back from its stance), then walks 1.4 m
   (to the right and 0.3 m back); the can's pose in the hand is measured throughout (the simulator's poses,
   for the measure only). Turning as it walks, goPos's path bulges 0.25 m forward: into the table.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import robot.generate as gen
from app.service import OperatorService
from app.service.local import LocalRobot

pytestmark = pytest.mark.slow

EDGE_X_M = 0.78
CAN_XY_M = (EDGE_X_M + 0.15, -0.22)
WALK_M = 1.4
#: Required [issue 11]: < 5 mm; measured 3.43 mm max (1.6 mm margin; 3.28 mm before leg odometry and the grasp
#: closing 10 mm past the can's centre, take_can.GRASP_PAST_CENTRE_M).
SLIP_LIMIT_M = 0.005


def can_in_hand(plant) -> np.ndarray:
    d = plant.data
    R_hand = d.body("RARM_LINK5").xmat.reshape(3, 3)
    return R_hand.T @ (d.body("can").xpos - d.body("RARM_LINK5").xpos)


def run_to_end(robot, service, run_id, timeout_s=90.0, on_tick=None):
    for _ in range(int(timeout_s / robot.loop.dt_control_s)):
        obs = robot.step()
        assert not obs.fallen
        if on_tick is not None:
            on_tick()
        status = service.get_run(run_id)
        if status.state != "running":
            return status
    raise AssertionError(f"run {run_id} still running after {timeout_s} s")


def test_a_grasped_can_slips_less_than_5_mm_through_a_1_4_m_walk():
    robot = LocalRobot("expo", speed=None)
    service = OperatorService(robot)
    plant = robot.plant
    plant.place_object("table", (EDGE_X_M + gen.EXPO_TABLE_SIZE_M[0] / 2, 0.0))
    plant.place_object("can", CAN_XY_M)
    robot.run_for(2.5)
    look = {"x_m": CAN_XY_M[0], "y_m": CAN_XY_M[1], "z_m": 0.75}
    status = run_to_end(robot, service, service.run_behavior("locate_can", look))
    assert status.state == "succeeded", status.message
    status = run_to_end(robot, service, service.run_behavior("take_can", {"table_edge_x_m": EDGE_X_M}))
    assert status.state == "succeeded", status.message
    ref = can_in_hand(plant)
    slips = []
    feet = robot.chain["op"].view().placed_in_world(robot.host.world_from_control()).feet_p_world_m  # the world
    on_tick = lambda: slips.append(float(np.linalg.norm(can_in_hand(plant) - ref)))  # noqa: E731
    turn = {"x_m": float(feet[0]), "y_m": float(feet[1]), "theta_deg": -90.0}
    status = run_to_end(robot, service, service.run_behavior("walk_to", turn), on_tick=on_tick)
    assert status.state == "succeeded", status.message
    walk = {"x_m": float(feet[0]) - 0.3, "y_m": float(feet[1]) - math.sqrt(WALK_M ** 2 - 0.3 ** 2),
            "theta_deg": -90.0}
    status = run_to_end(robot, service, service.run_behavior("walk_to", walk), on_tick=on_tick)
    robot.close()
    print(f"slip through the {WALK_M} m walk: max {1e3 * max(slips):.2f} mm")
    assert status.state == "succeeded", status.message
    assert max(slips) < SLIP_LIMIT_M
