"""Scenario: [OP] Fig. 8's unknown trash as `hrp2-console experiment trash --trials 4 --workers 2` runs it (a
seeded sample, the first four of the documented 10): the trash found by colour segmentation from the head camera
(no model), walked to, picked from the floor with the right hand (squat), the robot standing up with it and
raising it to the carry pose; then carried to the trash box and dropped in.

What holds (asserted): every location within 20 mm of the truth; the trash lifted >= 50 mm off the floor and
dropped into the box in at least 3 of 4 trials (measured 4/4; the CLI's 10: docs/fig8-tasks.md); the robot never
falls. The simulator's poses only place the trash and measure the outcome."""

from __future__ import annotations

import pytest

from app.lab.experiments.expo import run_trials
from app.lab.experiments.trash import placements, run_trial, summary_table

pytestmark = [pytest.mark.slow, pytest.mark.pool]

TRIALS = 4  # the CLI runs 10
SEED = 8  # the CLI's default: these are its first four trials
LOCATE_LIMIT_MM = 20.0  # measured 2.9-8.1 mm
LIFTED_MIN_M = 0.05  # the hand lifts 0.10 m; measured 81-95 mm


@pytest.fixture(scope="module")
def results():
    out = sorted(run_trials(placements(TRIALS, SEED), workers=2, run=run_trial), key=lambda r: r.trial)
    print("\n" + summary_table(out))
    return out


def test_segmentation_locates_the_trash_within_20_mm(results):
    errors = [r.locate_error_mm for r in results]
    assert all(e is not None and e < LOCATE_LIMIT_MM for e in errors), errors


def test_the_trash_is_picked_from_the_floor_in_three_of_four_trials_and_the_robot_never_falls(results):
    assert [r.trial for r in results if r.fallen] == []
    assert sum(r.lifted_m is not None and r.lifted_m >= LIFTED_MIN_M for r in results) >= 3, \
        [(r.trial, r.lifted_m, r.verdict) for r in results]


def test_the_trash_ends_in_the_box_in_three_of_four_trials(results):
    assert sum(r.succeeded and r.in_box for r in results) >= 3, [(r.trial, r.verdict) for r in results]
