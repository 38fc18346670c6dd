"""Scenario: the EXPO behaviours of [OP] VI on the real chain, as the experiment runs them
(`app.lab.experiments.expo.run_trial`: locate_can -> take_can -> locate_trash_box -> throw_can through the
operator service, as fast as possible). The simulator's poses only measure the errors.

1. One full trial (the can 0.15 m in from the near edge on the table's middle, the robot 1.5 m away): the can
   ends in the box, the location and release errors under [OP] VI's 40 mm, no fall.
2. The perception behaviours' results: published in the run's result (object, position, sigma, image region)
   and remembered for the later behaviours.
"""

from __future__ import annotations

import pytest

from app.lab.experiments.expo import run_trial

pytestmark = pytest.mark.slow

#: [OP] VI: location + motion error under 40 mm (measured: location 0.5 mm, release 7.4 mm)
ERROR_LIMIT_MM = 40.0


@pytest.fixture(scope="module")
def trial():
    return run_trial(0.0, 0.15, 1.5)


def test_one_expo_trial_puts_the_can_in_the_box(trial):
    print(trial)
    assert not trial.fallen
    assert trial.in_box, trial.verdict
    assert trial.succeeded, trial.verdict


def test_the_robot_sees_where_the_can_landed_as_it_did(trial):
    """throw_can's look at the box after the release (its images) says what the simulator's pose says."""
    assert trial.landing_verdict == ("in the box" if trial.in_box else "out of the box")


def test_the_can_is_located_and_released_within_40_mm(trial):
    assert trial.can_location_error_mm is not None and trial.can_location_error_mm < ERROR_LIMIT_MM
    assert trial.release_error_mm is not None and trial.release_error_mm < ERROR_LIMIT_MM
