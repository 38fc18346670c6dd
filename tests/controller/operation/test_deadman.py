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
