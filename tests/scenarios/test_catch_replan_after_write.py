"""The capture step's re-plan made after the command is written (AutoBalancer.after_write) instead of in the tick:
the same AutoBalancer output, float for float, as the tick computing it, through a catch left alone and through one
whose next tick a boundary command changes (new gait parameters, the hard e-stop pressed mid-swing)."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest

from app.lab.bench_scenarios import CATCH_PUSH, CATCH_PUSH_AFTER_S, CATCH_WALK_START_S
from app.service.local import LocalRobot
from app.service.verbs import GoVelocity, Push, SetParams
from controller.core.layer import Layer
from controller.layers.auto_balancer import AutoBalancer
from controller.walking.emergency_step import EmergencyStepPlan


def _catch(interrupt: bool) -> tuple[str, int]:
    """The bench's catch (the push late in a swing), 0.8 s of it: a hash of every AutoBalancer output, the ticks."""
    robot = LocalRobot("default", speed=None)
    robot.run_for(CATCH_WALK_START_S)
    robot.submit(GoVelocity(0.1, 0.0, 0.0)).result()
    robot.run_for(CATCH_PUSH_AFTER_S)
    body, impulse_ns, direction_deg, duration_s = CATCH_PUSH
    yaw = math.radians(direction_deg)
    force = (impulse_ns / duration_s * math.cos(yaw), impulse_ns / duration_s * math.sin(yaw), 0.0)
    robot.submit(Push(body, force, duration_s)).result()
    h, catching = hashlib.sha256(), 0
    abc = robot.chain["abc"]
    for _ in range(160):
        robot.step()
        out = abc._last_out
        for a in (out.q_rad, out.base_pos_world, out.gait.zmp_world, out.gait.cog_world):
            h.update(np.ascontiguousarray(a).tobytes())
        catching += abc.emergency_step
        if interrupt and catching == 20:  # mid-swing: the next tick's re-plan is prepared by now
            robot.submit(SetParams((("abc", (("emergency_step.cp_margin_m", 0.01), ("step_time_s", 0.8))),))).result()
        if interrupt and catching == 30:
            robot.estop()
    return h.hexdigest(), catching


@pytest.mark.parametrize("interrupt", [False, True], ids=["left-alone", "params-then-estop"])
def test_the_re_plan_made_after_the_write_gives_the_outputs_of_the_tick_computing_it(interrupt, monkeypatch):
    adopted = []
    adopt = EmergencyStepPlan.adopt
    monkeypatch.setattr(EmergencyStepPlan, "adopt", lambda self, other: adopted.append(1) or adopt(self, other))
    ahead, catching = _catch(interrupt)
    assert catching >= 30 and len(adopted) > 20  # the catch's re-plans came from after_write
    monkeypatch.setattr(AutoBalancer, "after_write", Layer.after_write)  # no after-write work: the tick re-plans
    adopted.clear()
    assert _catch(interrupt) == (ahead, catching)
    assert adopted == []
