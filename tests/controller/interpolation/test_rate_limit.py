"""approach: a value moved toward a target at a bounded rate."""

import pytest

from controller.interpolation.rate_limit import approach


@pytest.mark.parametrize(("value", "target", "step", "expected"), [
    (0.0, 0.04, 0.01, 0.01),     # up by one step
    (0.035, 0.04, 0.01, 0.04),   # up, landing on the target exactly
    (0.04, 0.0, 0.0025, 0.0375),  # down by one step
    (0.001, 0.0, 0.0025, 0.0),   # down, landing on it
    (0.02, 0.02, 0.01, 0.02),    # there: stays
])
def test_it_moves_by_at_most_the_step_and_stops_on_the_target(value, target, step, expected):
    assert approach(value, target, step) == expected


def test_ticks_reach_the_target_in_the_time_the_rate_gives():
    value, ticks = 0.0, 0
    while value != 0.5:
        value, ticks = approach(value, 0.5, 0.25 * 0.125), ticks + 1
    assert ticks == 16  # 0.5 m at 0.25 m/s with 0.125 s ticks: 2 s (binary-exact numbers)
