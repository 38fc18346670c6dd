"""OperationLayer's foot points at the layer level (no simulation): the target waits while the AutoBalancer
balances, integrates once the foot is lifted, is put down when nothing drives it, the refusals while walking, and
the motion stop publishing the offset its revert went back to."""

import dataclasses

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.core.types import Ports
from controller.operation.points import Twist
from controller.walking.foot_lift import CLEARANCE_M
from tests.controller.layers.test_operation import DT, gait_port, layer, run


@pytest.fixture(scope="module")
def shared_ik():
    from controller.layers.operation import OperationLayer

    return OperationLayer(DT).ik


def lifted_port(offset=(0.0, 0.0, 0.0)) -> Ports:
    """The AutoBalancer's gait with the right foot lifted by `offset` [m] (support on the left sole)."""
    g = gait_port(False, 0.0).gait
    return Ports(gait=dataclasses.replace(g, support="lleg", contact=(False, True),
                                          p_rsole_world=g.p_rsole_world + np.array(offset),
                                          foot_lift=("rfoot", tuple(offset))))


def commands(op, ticks, ports, twist, t0=0.0):
    """The foot commands published over `ticks` ticks with `twist` streamed at rfoot (None: nothing streamed)."""
    from tests.controller.fakes import make_ctx
    from tests.controller.layers.test_operation import REF

    out = []
    for k in range(ticks):
        t = t0 + k * DT
        if twist is not None:
            op.set_motion("rfoot", twist, t)
        ctx = make_ctx(t=t, tick=k)
        ctx.last_ports = ports
        op.tick(ctx, REF)
        out.append(ctx.ports.foot_command)
    return out


def test_the_foot_waits_while_balancing_then_integrates_then_goes_down_when_let_go(shared_ik):
    op = layer(shared_ik)
    up = Twist.of((0.0, 0.0, 0.05))
    cmds = commands(op, 10, gait_port(False, 0.0), up)  # the COM not over the left foot yet
    assert all(c is not None and c.foot == "rfoot" and c.offset_m == (0.0, 0.0, 0.0) for c in cmds)
    assert op.status().points["rfoot"].limited == "balancing"
    # lifted: from the lift's clearance (the reach's floor), then 0.05 m/s for the 19 ticks after
    cmds = commands(op, 20, lifted_port(), up, t0=10 * DT)
    assert cmds[0].offset_m == pytest.approx((0.0, 0.0, CLEARANCE_M))
    assert cmds[-1].offset_m == pytest.approx((0.0, 0.0, CLEARANCE_M + 19 * 0.05 * DT))
    assert op.status().points["rfoot"].limited is None
    cmds = commands(op, 1, lifted_port((0.0, 0.0, 0.005)), None, t0=1.0)  # the stream stopped (dead-man)
    assert cmds == [None] and op.status().points["rfoot"].target is None


def test_feet_are_refused_while_walking_and_the_walk_while_a_foot_is_operated(shared_ik):
    op = layer(shared_ik)
    run(op, 1, ports=gait_port(True, 0.0))
    with pytest.raises(InvalidCommand, match="rfoot: refused while walking"):
        op.set_motion("rfoot", Twist.of((0.0, 0.0, 0.05)), DT)
    with pytest.raises(InvalidCommand, match="lfoot: refused while walking"):
        op.set_behavior({"lfoot": Twist.of((0.0, 0.0, 0.05))})
    op = layer(shared_ik)
    commands(op, 2, lifted_port(), Twist.of((0.0, 0.0, 0.05)))
    with pytest.raises(InvalidCommand, match="walk: refused while the rfoot is operated"):
        op.set_motion("walk", Twist.of((0.1, 0.0, 0.0)), 2 * DT)
    with pytest.raises(InvalidCommand, match="lfoot: the rfoot is operated"):
        op.set_motion("lfoot", Twist.of((0.0, 0.0, 0.05)), 2 * DT)


def test_the_motion_stop_publishes_the_offset_its_revert_went_back_to(shared_ik):
    op = layer(shared_ik)
    commands(op, 1, gait_port(False, 0.0), Twist.of((0.0, 0.0, 0.05)))
    # from the clearance at t = DT to 34.75 mm at t = 0.5 s
    cmds = commands(op, 100, lifted_port(), Twist.of((0.0, 0.0, 0.05)), t0=DT)
    assert cmds[-1].offset_m[2] == pytest.approx(CLEARANCE_M + 99 * 0.05 * DT)
    stopped = dataclasses.replace(lifted_port((0.0, 0.0, 0.035)), motion_stopped=True, motion_reverted_to_s=0.25)
    cmds = commands(op, 5, stopped, Twist.of((0.0, 0.0, 0.05)), t0=101 * DT)
    assert cmds[-1].offset_m[2] == pytest.approx(CLEARANCE_M + 49 * 0.05 * DT, abs=0.0003)  # where it was at 0.25 s
    assert op.status().points["rfoot"].limited == "motion_stop"
    stopped = dataclasses.replace(stopped, motion_reverted_to_s=-1.0)  # before the foot was operated: down
    assert commands(op, 1, stopped, None, t0=106 * DT) == [None]
