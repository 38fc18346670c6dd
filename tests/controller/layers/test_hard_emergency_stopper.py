"""HardEmergencyStopper: latched freeze, blended release."""

import numpy as np
import pytest

from controller.core.errors import InvalidState
from controller.core.types import Reference
from controller.layers.hard_emergency_stopper import HardEmergencyStopper, HardEmergencyStopperParams
from tests.controller.fakes import make_ctx

DT = 0.005


def ramp(k):
    """A moving input: every joint at 0.001 rad per tick."""
    return Reference.from_arrays(np.full(30, 0.001 * k))


def test_disengaged_stopper_passes_the_input_through():
    hes = HardEmergencyStopper(np.zeros(30))
    ref = ramp(3)
    assert hes.tick(make_ctx(), ref) is ref


def test_engaged_stopper_holds_the_last_output_whatever_comes_in():
    hes = HardEmergencyStopper(np.zeros(30))
    for k in range(10):
        hes.tick(make_ctx(), ramp(k))
    hes.engage()
    outs = np.array([hes.tick(make_ctx(), ramp(k)).q_rad for k in range(10, 600)])
    assert np.max(np.abs(outs - 0.009)) < 1e-12
    assert hes.status().engaged is True


def test_engaging_twice_keeps_the_first_frozen_posture():
    hes = HardEmergencyStopper(np.zeros(30))
    hes.tick(make_ctx(), ramp(5))
    hes.engage()
    hes.tick(make_ctx(), ramp(6))
    hes.engage(np.ones(30))
    assert np.allclose(hes.tick(make_ctx(), ramp(7)).q_rad, 0.005)


def test_release_blends_to_the_live_input_without_a_jump_and_then_passes_through():
    hes = HardEmergencyStopper(np.zeros(30), HardEmergencyStopperParams(recover_time_s=1.0))
    hes.engage(np.zeros(30))
    hes.release()
    target = Reference.from_arrays(np.full(30, 0.5))
    outs = [hes.tick(make_ctx(), target).q_rad[0] for _ in range(int(1.0 / DT) + 5)]
    steps = np.abs(np.diff(np.r_[0.0, outs]))
    assert np.max(steps) < 0.5 * 1.875 * DT / 1.0 * 1.05  # min-jerk peak velocity 1.875 * distance / T
    assert outs[-1] == pytest.approx(0.5, abs=1e-12)
    assert hes.tick(make_ctx(), target) is target


def test_release_when_not_engaged_is_an_invalid_state():
    with pytest.raises(InvalidState, match="not engaged"):
        HardEmergencyStopper(np.zeros(30)).release()


def test_the_ports_say_held_while_engaged_and_releasing_during_the_blend():
    hes = HardEmergencyStopper(np.zeros(30), HardEmergencyStopperParams(recover_time_s=0.1))
    ctx = make_ctx()
    hes.tick(ctx, ramp(1))
    assert not ctx.ports.hold and not ctx.ports.releasing
    hes.engage()
    ctx = make_ctx()
    hes.tick(ctx, ramp(2))
    assert ctx.ports.hold and not ctx.ports.releasing
    hes.release()
    for _ in range(int(0.1 / DT)):  # the blend's ticks (the ports are set before each steps it)
        ctx = make_ctx()
        hes.tick(ctx, ramp(2))
        assert ctx.ports.hold and ctx.ports.releasing
    ctx = make_ctx()
    hes.tick(ctx, ramp(2))
    assert not ctx.ports.hold and not ctx.ports.releasing


def test_the_release_blend_carries_the_motion_the_balance_layers_resume_with():
    # the balance layers resume at the release (Ports.releasing): what they move passes unscaled on top of the
    # gap between the frozen command and the live input, which is blended out
    hes = HardEmergencyStopper(np.zeros(30), HardEmergencyStopperParams(recover_time_s=1.0))
    hes.engage(np.zeros(30))
    hes.release()
    outs = np.array([hes.tick(make_ctx(), ramp(k)).q_rad[0] for k in range(int(1.0 / DT))])
    moved = 0.001 * np.arange(int(1.0 / DT))
    assert outs[0] == pytest.approx(0.0, abs=1e-6)
    np.testing.assert_allclose(outs, moved, atol=1e-12)  # no gap at the release: the input's motion exactly
