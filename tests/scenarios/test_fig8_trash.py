"""Scenario: [OP] Fig. 8's unknown trash as `hrp2-console experiment trash --trials 4 --workers 2` runs it (a
seeded sample of the documented 10: a trial simulates ~90 s): the trash found by colour segmentation from the
head camera, picked from the floor with the right hand (squat), carried to the trash box and dropped in. At
least 3 of the 4 end in the box, the robot never falls, every location within 20 mm of the truth.

The simulator's poses only place the trash and measure the outcome (docs/fig8-tasks.md has the figures)."""

from __future__ import annotations

import pytest

from app.lab.experiments.expo import run_trials
from app.lab.experiments.trash import placements, run_trial, summary_table

pytestmark = pytest.mark.slow

TRIALS = 4  # the CLI runs 10; 4 fit CI's time
SEED = 8  # the CLI's default: these are its first four trials
LOCATE_LIMIT_MM = 20.0


@pytest.fixture(scope="module")
def results():
    out = sorted(run_trials(placements(TRIALS, SEED), workers=2, run=run_trial), key=lambda r: r.trial)
    print("\n" + summary_table(out))
    return out


def test_the_trash_ends_in_the_box_in_three_of_four_trials_and_the_robot_never_falls(results):
    assert len(results) == TRIALS
    assert [r.trial for r in results if r.fallen] == []
    assert sum(r.succeeded and r.in_box for r in results) >= 3, [(r.trial, r.verdict) for r in results]


def test_segmentation_locates_the_trash_within_20_mm(results):
    errors = [r.locate_error_mm for r in results]
    assert all(e is not None and e < LOCATE_LIMIT_MM for e in errors), errors
