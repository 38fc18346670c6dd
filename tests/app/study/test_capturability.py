"""The LIP capturability of a push: known cases (no push, a push the ankles absorb, one no step reaches) and the
standing bound it gives against the one measured in the simulation."""

import math

import pytest

from app.lab.study.capturability import GaitTiming, Lip, StepLimits, gait_moment, push_capturability

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

#: HRP-2 as the AutoBalancer sees it: 58.0 kg, COM 0.8105 m above the soles (omega 3.48 1/s)
LIP = Lip(58.0, 0.8105)
STANDING = 0.05  # a phase inside the first double support: with speed 0 the soles side by side
FORWARD, LEFT, BACKWARD = 0.0, math.pi / 2, math.pi


def largest_absorbed(direction_rad, phase=STANDING, speed=0.0, steps=0):
    return max(j for j in range(0, 120) if (c := push_capturability(j, direction_rad, phase, speed, LIP)).steps
               is not None and c.steps <= steps)


def test_no_push_is_capturable_with_zero_steps_at_every_phase_and_speed():
    for phase in [k / 16 for k in range(16)]:
        for speed in (0.0, 0.1, 0.2):
            c = push_capturability(0.0, FORWARD, phase, speed, LIP)
            assert c.steps == 0, (phase, speed, c)
            assert c.ankle_margin_m > 0.0


def test_a_small_push_stays_within_the_sole_and_needs_no_step():
    c = push_capturability(5.0, FORWARD, 0.3, 0.1, LIP)  # single support on the right foot
    assert c.steps == 0 and c.swing_leg is None
    assert -0.0936 < c.cp_push_end_xy[0] < 0.1236  # inside the stance sole


def test_the_standing_bound_is_the_measured_one_within_two_newton_seconds():
    # measured standing (docs/measurements/walking-and-balance.md): 28 N s forward, 20 backward, 40 sideways
    # absorbed without a step
    assert abs(largest_absorbed(FORWARD) - 28) <= 2
    assert abs(largest_absorbed(BACKWARD) - 20) <= 2
    assert abs(largest_absorbed(LEFT) - 40) <= 2


def test_a_step_catches_twice_the_forward_bound_standing_but_not_sideways():
    c = push_capturability(56.0, FORWARD, STANDING, 0.0, LIP)  # stands in the simulation with the emergency step
    assert c.steps == 1 and c.landing_xy[0] > 0.3 and c.touchdown_s == pytest.approx(0.29)
    # sideways a step would have to cross the stance leg (docs/measurements/walking-and-balance.md: the LIP says
    # 60 N s cannot be caught)
    assert push_capturability(60.0, LEFT, STANDING, 0.0, LIP).steps is None


def test_a_push_beyond_any_reach_is_not_capturable():
    c = push_capturability(150.0, FORWARD, STANDING, 0.0, LIP)
    assert c.steps is None and c.step_margin_m < 0.0
    assert c.landing_xy[0] == pytest.approx(0.55)  # the leg's forward reach from the stance sole at x = 0


def test_a_push_toward_the_stance_side_in_single_support_cannot_be_stepped_by_the_swing_foot():
    # right foot on the ground, left in the air: pushed to the right, the left foot cannot cross over
    phase = 0.3  # 0.6 s after the right touchdown
    assert gait_moment(phase, 0.1).support == "rleg"
    c = push_capturability(20.0, -LEFT, phase, 0.1, LIP)
    assert c.steps is None and c.swing_leg == "lleg"
    # pushed to the left the left foot lands on the left and catches it
    assert push_capturability(20.0, LEFT, phase, 0.1, LIP).steps == 1


def test_the_gait_moment_follows_the_step_timing():
    t = GaitTiming()
    assert gait_moment(0.0, 0.1).support == "both"  # right touchdown
    assert gait_moment(0.2 / t.cycle_s + 1e-6, 0.1).support == "rleg"
    m = gait_moment(0.3, 0.1)
    assert (m.swing_elapsed_s, m.swing_left_s) == (pytest.approx(0.4), pytest.approx(0.4))
    assert gait_moment(1.0 / t.cycle_s + 1e-6, 0.1).support == "both"
    assert gait_moment(1.2 / t.cycle_s + 1e-6, 0.1).support == "lleg"


def test_a_swing_just_lifted_lands_no_sooner_than_the_fastest_step():
    limits = StepLimits.of()
    assert limits.min_swing_s == pytest.approx(0.24) and limits.min_touchdown_s == pytest.approx(0.29)
    phase = (0.2 + 0.01) / GaitTiming().cycle_s  # the left foot lifted 0.01 s ago
    c = push_capturability(30.0, FORWARD, phase, 0.1, LIP)
    assert c.touchdown_s == pytest.approx(0.23)


def test_invalid_input_is_refused():
    with pytest.raises(ValueError):
        push_capturability(-1.0, FORWARD, 0.0, 0.1, LIP)
    with pytest.raises(ValueError):
        Lip(0.0, 0.8)


def test_the_largest_capturable_impulse_is_the_boundary_of_the_verdicts():
    from app.lab.study.capturability import largest_capturable_ns

    j0 = largest_capturable_ns(FORWARD, STANDING, 0.0, LIP, steps=0)
    j1 = largest_capturable_ns(FORWARD, STANDING, 0.0, LIP, steps=1)
    assert 26.0 < j0 < 31.0 and j1 > 2 * j0  # the ankles' bound, and a step's beyond it
    assert push_capturability(j0 - 0.5, FORWARD, STANDING, 0.0, LIP).steps == 0
    assert push_capturability(j0 + 0.5, FORWARD, STANDING, 0.0, LIP).steps == 1
    assert push_capturability(j1 + 0.5, FORWARD, STANDING, 0.0, LIP).steps is None
