"""The 200 ms dead-man with its ~100 ms ramp (unit)."""

import pytest

from controller.core.errors import InvalidCommand
from controller.operation.deadman import DEADMAN_RAMP_S, DEADMAN_TIMEOUT_S, deadman_factor


def test_a_fresh_setpoint_counts_in_full_up_to_200_ms():
    assert DEADMAN_TIMEOUT_S == 0.2 and DEADMAN_RAMP_S == 0.1
    for age in (-0.01, 0.0, 0.1, 0.2):
        assert deadman_factor(age) == 1.0


def test_an_old_setpoint_ramps_down_instead_of_snapping():
    ages = [0.2 + 0.005 * k for k in range(25)]
    factors = [deadman_factor(a) for a in ages]
    assert factors[0] == 1.0 and factors[-1] == 0.0
    steps = [a - b for a, b in zip(factors, factors[1:], strict=False)]
    assert all(0.0 <= s <= 0.05 + 1e-12 for s in steps)  # at most 5 % per 5 ms tick: no snap
    assert deadman_factor(0.25) == pytest.approx(0.5)


def test_a_setpoint_older_than_300_ms_counts_as_zero():
    assert deadman_factor(0.3) == 0.0 and deadman_factor(10.0) == 0.0


def test_zero_ramp_snaps_and_negative_times_are_refused():
    assert deadman_factor(0.2001, ramp_s=0.0) == 0.0
    with pytest.raises(InvalidCommand, match="ramp_s"):
        deadman_factor(0.1, ramp_s=-1.0)


def test_live_twists_weigh_each_setpoint_by_its_age_and_forget_the_expired():
    from controller.operation.deadman import live_twists
    from controller.operation.points import Twist

    fresh, fading, gone = Twist.of((0.1, 0.0, 0.0)), Twist.of((0.2, 0.0, 0.0)), Twist.of((0.3, 0.0, 0.0))
    setpoints = {"rhand": (fresh, 1.0), "lhand": (fading, 0.75), "waist": (gone, 0.5)}
    out = live_twists(setpoints, 1.0)
    assert out["rhand"] is fresh  # under the timeout: the same object, not a copy
    assert out["lhand"].linear_m_s[0] == pytest.approx(0.1)  # 0.25 s old: half way down the ramp
    assert "waist" not in out and set(setpoints) == {"rhand", "lhand"}


def test_streamed_setpoints_keep_the_latest_per_point_and_fade_out_under_the_dead_man():
    from controller.core.types import WalkCommand
    from controller.operation.deadman import StreamedSetpoints
    from controller.operation.points import Twist

    s = StreamedSetpoints()
    assert not s and s.live(0.0) == {}
    old, new = Twist.of((0.1, 0.0, 0.0)), Twist.of((0.2, 0.0, 0.0))
    s.set("rhand", old, 0.0)
    s.set("rhand", new, 0.1)  # the latest replaces the earlier
    steps = WalkCommand(0.0, 0.0, 0.0, max_stride_m=0.15)
    s.set("walk", Twist.of((0.1, 0.0, 0.0)), 0.1, steps)
    assert s.live(0.2)["rhand"] is new and s.walk_steps is steps
    assert s.live(0.35)["rhand"].linear_m_s[0] == pytest.approx(0.1)  # 0.25 s old: half way down
    assert s.live(0.5) == {} and not s  # faded out: forgotten
    assert s.walk_steps is steps  # the step parameters outlive the setpoint (the next walk takes them)
    s.set("head", Twist.of(angular_rad_s=(0.0, 0.1, 0.0)), 1.0)
    assert s.clear() is True and s.clear() is False
