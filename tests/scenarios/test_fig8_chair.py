"""Scenario: [OP] Fig. 8's chair as `hrp2-console experiment chair --trials 4 --workers 2` runs it (a seeded
sample, the first four of the documented 10): chair placements +-3 cm, +-5 cm, +-10 deg, the left hand grasps the
backrest's rail and pushes the chair 0.12 m; at least 3 of 4 end within 30 mm of the goal, turned < 10 deg,
upright; the robot never falls.

The simulator's poses only place the chair and measure the outcome (docs/fig8-tasks.md has the figures)."""

from __future__ import annotations

import pytest

from app.lab.experiments.chair import GOAL_TOL_M, UPRIGHT_TOL_DEG, placements, run_trial, summary_table
from app.lab.experiments.expo import run_trials

pytestmark = [pytest.mark.slow, pytest.mark.pool]

TRIALS = 4  # the CLI runs 10
SEED = 8  # the CLI's default: these are its first four trials


@pytest.fixture(scope="module")
def results():
    out = sorted(run_trials(placements(TRIALS, SEED), workers=2, run=run_trial), key=lambda r: r.trial)
    print("\n" + summary_table(out))
    return out


def test_three_of_four_chairs_reach_their_goal_upright_and_the_robot_never_falls(results):
    assert len(results) == TRIALS
    assert [r.trial for r in results if r.fallen] == []
    ok = [r for r in results if r.succeeded]
    assert len(ok) >= 3, [(r.trial, r.verdict) for r in results if not r.succeeded]
    assert all(r.goal_error_m < GOAL_TOL_M and r.max_tilt_deg < UPRIGHT_TOL_DEG for r in ok)
