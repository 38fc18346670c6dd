"""HardEmergencyStopper: latched freeze (after the step in progress has landed), blended release."""

from types import SimpleNamespace

import numpy as np
import pytest

from controller.core.errors import InvalidState
from controller.core.types import Reference, StepInProgress
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


# ---- the operator's e-stop during a step: it lands, then freezes ---------------------------------------------

STANDING = SimpleNamespace(walking=False)  # Ports.gait as hes reads it (a standing robot)
WALKING = SimpleNamespace(walking=True)


class StepTicker:
    """hes alone, ticked at control time k * DT with the ramp as its input and the ports the layers before it
    published this tick (the step in progress, the capture-point error, the gait)."""

    def __init__(self, params: HardEmergencyStopperParams | None = None):
        self.hes = HardEmergencyStopper(np.zeros(30), params)
        self.k = 0
        self.ports = None

    def tick(self, step=None, cp_error_m=0.0, gait=STANDING):
        ctx = make_ctx(t=self.k * DT, tick=self.k)
        ctx.ports.step, ctx.ports.cp_error_m, ctx.ports.gait = step, cp_error_m, gait
        out = self.hes.tick(ctx, ramp(self.k))
        self.ports = ctx.ports
        self.k += 1
        return out

    @property
    def t(self) -> float:  # [s] the start of the next tick
        return self.k * DT

    def freeze_time(self, press_s, step_at=lambda t: None, cp_error_at=lambda t: 0.0, gait=STANDING, until_s=1.0):
        """Tick to press_s, engage, tick on: the control time [s] from which the output no longer moves."""
        while self.t < press_s - 1e-9:
            self.tick(step_at(self.t), cp_error_at(self.t), gait)
        self.hes.engage()
        outs, times = [], []
        while self.t < until_s - 1e-9:
            times.append(self.t)
            outs.append(self.tick(step_at(self.t), cp_error_at(self.t), gait).q_rad[0])
        moving = np.flatnonzero(np.diff(outs) != 0.0)
        return times[0] if len(moving) == 0 else times[int(moving[-1]) + 1]


def test_standing_still_the_operators_e_stop_freezes_within_one_tick():
    t = StepTicker()
    for _ in range(10):
        t.tick(cp_error_m=0.001)
    t.hes.engage()
    first = t.tick(cp_error_m=0.001).q_rad
    assert t.hes.status().stopping is None and t.ports.hold and not t.ports.landing
    np.testing.assert_allclose(first, 0.009, atol=1e-12)  # the last output before the press, whatever comes in
    assert np.array_equal(t.tick().q_rad, first)


@pytest.mark.parametrize("touchdown_in_s", [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.285, 0.3])
def test_in_an_emergency_step_it_freezes_settle_after_the_touchdown_and_never_later_than_the_bound(touchdown_in_s):
    p = HardEmergencyStopperParams()
    press_s = 0.5
    step = StepInProgress(touchdown_time_s=press_s + touchdown_in_s, catching=True)
    frozen_at = StepTicker(p).freeze_time(press_s, step_at=lambda t: step)
    expected = min(press_s + touchdown_in_s + p.landing_settle_s, press_s + p.landing_max_s - DT)
    assert frozen_at == pytest.approx(expected, abs=1e-9)
    assert frozen_at - press_s <= p.landing_max_s


def test_while_landing_the_live_command_passes_the_balance_layers_run_and_the_status_says_so():
    t = StepTicker()
    step = StepInProgress(touchdown_time_s=0.2, catching=True)
    for _ in range(10):
        t.tick(step)
    t.hes.engage()
    ref = ramp(t.k)
    ctx = make_ctx(t=t.t)
    ctx.ports.step = step
    assert t.hes.tick(ctx, ref) is ref  # the step goes on under the command of abc and st
    assert ctx.ports.hold and ctx.ports.landing and not ctx.ports.releasing
    ctx.last_ports = ctx.ports
    assert ctx.hold and not ctx.balance_hold  # the motion layers hold, the balance layers run
    status = t.hes.status()
    assert status.engaged and status.stopping == "landing the step" and status.reason == "operator"
    assert 0.0 < status.landing_remaining_s <= HardEmergencyStopperParams().landing_max_s


@pytest.mark.parametrize("touchdown_in_s", [0.05, 0.15, 0.3, 0.34])
def test_a_walks_swing_landing_within_the_bound_freezes_at_its_touchdown(touchdown_in_s):
    press_s = 0.5
    td = press_s + touchdown_in_s
    # abc's port: the swing until its touchdown, nothing in the double support after it
    frozen_at = StepTicker().freeze_time(press_s, step_at=lambda t: StepInProgress(td, False) if t < td - 1e-9
                                         else None, gait=WALKING)
    assert frozen_at == pytest.approx(td, abs=1e-9)


@pytest.mark.parametrize("touchdown_in_s", [0.36, 0.5, 0.8])
def test_a_walks_swing_landing_later_than_the_bound_and_not_cut_freezes_at_once(touchdown_in_s):
    step = StepInProgress(0.5 + touchdown_in_s, False)
    assert StepTicker().freeze_time(0.5, step_at=lambda t: step, gait=WALKING) == pytest.approx(0.5, abs=1e-9)


@pytest.mark.parametrize("touchdown_in_s", [0.36, 0.5, 0.8])
def test_a_walks_later_swing_that_abc_cuts_short_lands_as_a_catch_and_then_freezes(touchdown_in_s):
    # abc's port says the swing would be cut to land 0.26 s after the next tick; a tick after the press it is
    # (EmergencyStepping.cut): the port becomes a catching step down 0.25 s later, settled landing_settle_s after
    p, press_s, cut_s = HardEmergencyStopperParams(), 0.5, 0.26
    walk_swing = StepInProgress(press_s + touchdown_in_s, False, cut_swing_s=cut_s)
    catch = StepInProgress(press_s + DT + 0.25, True)
    frozen_at = StepTicker(p).freeze_time(press_s, step_at=lambda t: walk_swing if t < press_s + DT - 1e-9
                                          else catch, gait=WALKING)
    assert frozen_at == pytest.approx(min(catch.touchdown_time_s + p.landing_settle_s,
                                          press_s + p.landing_max_s - DT), abs=1e-9)
    assert frozen_at > catch.touchdown_time_s  # not in the air


@pytest.mark.parametrize("landing_max_s", [0.0, 0.1, 0.25])
def test_a_swing_cut_short_later_than_a_shortened_bound_freezes_at_once(landing_max_s):
    p = HardEmergencyStopperParams(landing_max_s=landing_max_s)
    step = StepInProgress(1.3, False, cut_swing_s=0.26)
    assert StepTicker(p).freeze_time(0.5, step_at=lambda t: step, gait=WALKING) == pytest.approx(0.5, abs=1e-9)


def test_a_pushed_robot_standing_balances_on_until_its_emergency_step_has_landed():
    # the press comes before the capture point leaves the soles: the step starts 0.06 s later, lands 0.285 s after
    p = HardEmergencyStopperParams()
    press_s, trigger_s = 0.5, 0.56
    step = StepInProgress(trigger_s + 0.2, True)
    frozen_at = StepTicker(p).freeze_time(press_s, step_at=lambda t: step if t >= trigger_s - 1e-9 else None,
                                          cp_error_at=lambda t: 0.05)
    assert frozen_at == pytest.approx(min(trigger_s + 0.2 + p.landing_settle_s, press_s + p.landing_max_s - DT))


def test_a_pushed_robot_that_the_ankles_catch_freezes_once_its_capture_point_error_is_back_under_the_threshold():
    p = HardEmergencyStopperParams()
    frozen_at = StepTicker(p).freeze_time(0.5, cp_error_at=lambda t: 0.03 if t < 0.6 - 1e-9 else 0.01)
    assert frozen_at == pytest.approx(0.6, abs=1e-9)
    # a push that stays: frozen at the bound
    frozen_at = StepTicker(p).freeze_time(0.5, cp_error_at=lambda t: 0.03)
    assert frozen_at == pytest.approx(0.5 + p.landing_max_s - DT, abs=1e-9)


def pressed_in_a_step() -> tuple[StepTicker, StepInProgress]:
    """An operator's e-stop pressed 0.05 s into an emergency step landing at 0.3 s, one tick later."""
    t = StepTicker()
    step = StepInProgress(0.3, True)
    for _ in range(10):
        t.tick(step)
    t.hes.engage()
    t.tick(step)
    return t, step


def test_a_fault_or_a_fall_while_a_step_lands_freezes_at_once_and_says_why():
    t, step = pressed_in_a_step()
    assert t.hes.landing
    t.hes.engage(reason="fallen")
    held = t.tick(step).q_rad
    assert not t.hes.landing and t.hes.reason == "fallen" and t.hes.status().stopping is None
    assert np.array_equal(t.tick(step).q_rad, held)


def test_release_while_a_step_lands_ends_the_stop_without_a_blend():
    t, step = pressed_in_a_step()
    t.hes.release()
    ref = ramp(t.k)
    ctx = make_ctx(t=t.t)
    assert t.hes.tick(ctx, ref) is ref
    assert not (ctx.ports.hold or ctx.ports.landing or ctx.ports.releasing)
    assert not t.hes.status().engaged and not t.hes.status().recovering


def test_an_e_stop_during_the_release_blend_freezes_where_the_blend_is_even_in_a_step():
    t = StepTicker(HardEmergencyStopperParams(recover_time_s=1.0))
    step = StepInProgress(1.0, True)
    for _ in range(10):
        t.tick(step)
    t.hes.engage()
    t.hes.engage(np.zeros(30), reason="fault")  # frozen at zero, far from the live ramp
    t.hes.release()
    for _ in range(20):
        blended = t.tick(step).q_rad
    t.hes.engage()
    assert t.hes.status().stopping is None
    np.testing.assert_array_equal(t.tick(step).q_rad, blended)  # no jump to the live command
