"""Scenario: the EXPO experiment of [OP] VI as `hrp2-console experiment expo --trials 20` runs it, 20 trials
with the default seed (random can placements along the table's near side, the robot 1.5-2.5 m away), two at a
time: every can ends in the box, every location and release error under the paper's 40 mm, no fall.

The simulator's poses only measure the errors; the robot locates the can and the box with its cameras.
Measured (this machine, `pytest -s tests/scenarios/test_expo_trials.py`): 20/20, can location error median 0.6 mm,
max 0.6 mm; release error median 7.8 mm, max 9.1 mm; 123-147 s simulated per trial."""

from __future__ import annotations

import numpy as np
import pytest

from app.lab.experiments.expo import placements, run_trials, summary_table

pytestmark = [pytest.mark.slow, pytest.mark.pool]

TRIALS = 20
SEED = 2005  # the CLI's default
#: [OP] VI: location + motion error under 40 mm
ERROR_LIMIT_MM = 40.0


@pytest.fixture(scope="module")
def results():
    # without throw_can's look at where the can landed (21 s of each trial's ~160, checked in test_expo_behaviors)
    out = sorted(run_trials(placements(TRIALS, SEED), workers=2, look_after=False), key=lambda r: r.trial)
    print("\n" + summary_table(out))
    return out


def test_twenty_of_twenty_cans_end_in_the_box_without_a_fall(results):
    assert len(results) == TRIALS
    failed = [(r.trial, r.verdict) for r in results if not (r.succeeded and r.in_box) or r.fallen]
    assert failed == []


def test_every_location_and_release_error_is_under_40_mm(results):
    locate = np.array([r.can_location_error_mm for r in results], dtype=float)
    release = np.array([r.release_error_mm for r in results], dtype=float)
    assert np.all(np.isfinite(locate)) and np.all(np.isfinite(release))
    assert locate.max() < ERROR_LIMIT_MM and release.max() < ERROR_LIMIT_MM
