"""Preview before motion, in simulation (in process): a walk_to preview's footsteps are the ones the AutoBalancer
walks and the feet land on; a take_can run in step mode runs one phase and then holds, the robot standing still,
until the next step."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from app.service import OperatorService
from app.service.local import LocalRobot
from controller.balance.leg_odometry import control_to_world

pytestmark = pytest.mark.slow

#: [m] the done-when's bound between the previewed and the walked footsteps
MATCH_M = 0.01
WARM_UP_S = 2.5  # [s] the AutoBalancer and the Stabilizer blend in; walking needs them running


@pytest.fixture
def robot():
    r = LocalRobot("expo", speed=None)
    yield r
    r.stop()


def _sole_xy(plant, body: str) -> np.ndarray:
    """Ground truth (verdict only): the ankle body's x, y, the sole's on a flat foot [m]."""
    return np.array(plant.data.xpos[mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_BODY, body)][:2])


def test_a_walk_to_preview_gives_the_footsteps_the_autobalancer_walks_and_the_feet_land_on(robot):
    service = OperatorService(robot)
    robot.run_for(WARM_UP_S)
    preview = service.preview_behavior("walk_to", {"x_m": 0.3, "y_m": 0.1, "theta_deg": 10.0})
    planned = preview["footsteps"]
    assert preview["complete"] and len(planned) >= 4
    run_id = service.run_behavior("walk_to", {"x_m": 0.3, "y_m": 0.1, "theta_deg": 10.0})
    robot.run_for(0.05)
    host = robot.host
    wfc = host.world_from_control()
    walked = [(("right" if f.leg == "rleg" else "left"), *control_to_world(wfc, (f.x, f.y, f.z))[:2], f.yaw + wfc[3])
              for f in host.layer("abc").gait.footsteps]
    assert [s["side"] for s in planned] == [w[0] for w in walked]
    off_m = max(math.hypot(s["x_m"] - w[1], s["y_m"] - w[2]) for s, w in zip(planned, walked, strict=True))
    off_rad = max(abs(s["yaw_rad"] - w[3]) for s, w in zip(planned, walked, strict=True))
    assert off_m <= MATCH_M and off_rad <= math.radians(0.5), (off_m, off_rad)
    robot.run_until(lambda obs: service.get_run(run_id).state != "running", 30.0)
    robot.run_for(1.0)
    assert service.get_run(run_id).state == "succeeded", service.get_run(run_id).message
    last = {side: next(s for s in reversed(planned) if s["side"] == side) for side in ("right", "left")}
    landed = {side: _sole_xy(robot.plant, body) for side, body in (("right", "RLEG_LINK5"), ("left", "LLEG_LINK5"))}
    landed_off_m = max(float(np.hypot(*(landed[s] - (last[s]["x_m"], last[s]["y_m"])))) for s in last)
    print(f"preview vs AutoBalancer plan: {off_m * 1e3:.2f} mm; final soles landed {landed_off_m * 1e3:.1f} mm off")
    assert landed_off_m <= MATCH_M, landed_off_m


def test_step_mode_runs_one_phase_of_take_can_and_waits_until_the_next_step(robot):
    service = OperatorService(robot)
    robot.run_for(WARM_UP_S)
    can, _ = robot.plant.object_pose("can")  # what a locate_can would have remembered (seeded: no camera here)
    robot.host.recognitions["can"] = {"object": "can", "position_m": [float(v) for v in can], "from_m": 1.0}
    preview = service.preview_behavior("take_can", {})
    assert [p["phase"] for p in preview["phases"]][:3] == ["tuck", "walk", "open"]
    run_id = service.run_behavior("take_can", {}, mode="step")
    robot.run_until(lambda obs: service.get_run(run_id).waiting, 15.0)  # the tuck (left hand) runs, then it holds
    run = service.get_run(run_id)
    assert run.state == "running" and run.result.get("phase") == "walk" and run.result["steps"][-1]["ok"]
    lhand0 = _body_xyz(robot.plant, "LARM_LINK6")
    robot.run_for(3.0)  # held: no walk starts, the hands stay
    run = service.get_run(run_id)
    assert run.state == "running" and run.waiting
    assert not robot.host.layer("abc").gait.walking
    assert np.linalg.norm(_body_xyz(robot.plant, "LARM_LINK6") - lhand0) < 0.005
    service.step_run(run_id)
    robot.run_for(2.0)
    assert robot.host.layer("abc").gait.walking and not service.get_run(run_id).waiting
    service.cancel_run(run_id)
    robot.run_for(3.0)
    assert service.get_run(run_id).state == "cancelled"


def _body_xyz(plant, body: str) -> np.ndarray:
    return np.array(plant.data.xpos[mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_BODY, body)])
