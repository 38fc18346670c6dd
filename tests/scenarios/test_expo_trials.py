"""Scenario: the EXPO experiment of [OP] VI, 20 trials two at a time: the four corners of the can's range ([OP] VI:
anywhere along the near long side, U = +-0.6 m from its middle, 0.10-0.30 m in from the near edge) at both ends of
the robot's start distance (1.5-2.5 m), then the first 16 placements of `hrp2-console experiment expo --trials 20`
(its default seed, uniform over the same ranges). Every can ends in the box, every location + release error is
under the paper's 40 mm, no fall.

The corners failed before take_can chose its stance from the table's edge and tucked the free arm, and before
throw_can walked along the table first: a can 0.29 m in left the feet 0.16 m from the edge and the open hand met it
(IK-limited 148 mm); walking to the box the left wrist met the table's corner leg (falls); and the far left corner's
can, taken 0.55 m out by a table leg, was 11 mm beyond the hand's reach over the hole until throw_can released 6 cm
above the lid (3 cm needed the forearm's roll at its limit). (They were a test of their own, four more trials.)

The simulator's poses only measure the errors; the robot locates the can and the box with its cameras.
Measured (this machine, `pytest -s tests/scenarios/test_expo_trials.py`, the seeded 20): 20/20, can location error
median 0.6 mm, max 0.6 mm; release error median 7.8 mm, max 9.1 mm; 123-147 s simulated per trial; the corners:
release errors 4.4-8.3 mm."""

from __future__ import annotations

import numpy as np
import pytest

from app.lab.experiments.expo import placements, run_trials, summary_table

pytestmark = [pytest.mark.slow, pytest.mark.pool]

TRIALS = 20
SEED = 2005  # the CLI's default
#: (U, V, robot distance) [m]: the range's corners, each at one end of the distance's
CORNERS = [
    (0.60, 0.30, 2.5),  # by a table leg: the can is taken 0.55 m out
    (-0.60, 0.30, 1.5),
    (0.60, 0.10, 1.5),
    (-0.60, 0.10, 2.5),
]
#: [OP] VI: location + motion error under 40 mm
ERROR_LIMIT_MM = 40.0


@pytest.fixture(scope="module")
def results():
    # without throw_can's look at where the can landed (21 s of each trial's ~160, checked in test_expo_behaviors)
    trials = CORNERS + placements(TRIALS - len(CORNERS), SEED)
    out = sorted(run_trials(trials, workers=2, look_after=False), key=lambda r: r.trial)
    print("\n" + summary_table(out))
    return out


def test_twenty_of_twenty_cans_end_in_the_box_without_a_fall(results):
    assert len(results) == TRIALS
    failed = [(r.trial, r.verdict) for r in results if not (r.succeeded and r.in_box) or r.fallen]
    assert failed == []


def test_every_location_plus_release_error_is_under_40_mm(results):
    locate = np.array([r.can_location_error_mm for r in results], dtype=float)
    release = np.array([r.release_error_mm for r in results], dtype=float)
    assert np.all(np.isfinite(locate)) and np.all(np.isfinite(release))
    assert (locate + release).max() < ERROR_LIMIT_MM, [(r.trial, r.can_location_error_mm, r.release_error_mm)
                                                       for r in results]
