"""Scenario: the fridge task of [OP] VI, Fig. 8 as `hrp2-console experiment fridge --trials 10 --through door`
runs it: 10 seeded fridge poses (shifted +-2 cm, turned +-4 deg) and can places, two at a time. The
right hand's `open_door` grasps the located handle and pulls the door along its arc while the operator's stick
raises the left hand in the same ticks (Eq. 5 for two points, read from the operation layer's status); the door
stays open and the can inside is located. The can's extraction by the left hand is not in CI: it does not work
yet (docs/fig8-tasks.md).

Measured (this machine, `pytest -s -m slow tests/scenarios/test_experiment_fridge.py`): 10/10, door 31.9-34.7 deg,
handle located 0.7-2.2 mm off, can 1.1-1.8 mm off, 696-698 two-point ticks; 35 s simulated per trial, 8-11 s wall
each; 53 s wall for the ten on 2 workers, the machine nearly idle (load average ~2) (docs/fig8-tasks.md)."""

from __future__ import annotations

import pytest

from app.lab.experiments.fridge import DOOR_OPEN_MIN_DEG, placements, run_trials, trial_line

pytestmark = [pytest.mark.slow, pytest.mark.pool]

TRIALS = 10
SEED = 8  # the CLI's default
#: [mm] the handle and the can located within this of where they are (measured <= 2.2 mm; ~8 mm margin)
LOCATE_LIMIT_MM = 10.0
#: the left hand's stick ran ~3.5 s beside the pull (measured ~700 ticks of 5 ms); at least 1 s of it counts
TWO_POINT_MIN_TICKS = 200


@pytest.fixture(scope="module")
def results():
    out = sorted(run_trials(placements(TRIALS, SEED), workers=2, through="door"), key=lambda r: r.trial)
    print("\n" + "\n".join(trial_line(r) for r in out))
    return out


def test_the_door_is_opened_and_held_without_a_fall_in_every_sampled_trial(results):
    assert len(results) == TRIALS
    failed = [trial_line(r) for r in results if not r.succeeded or r.fallen or r.door_deg < DOOR_OPEN_MIN_DEG]
    assert failed == []


def test_the_handle_and_the_can_are_located_from_the_head_camera(results):
    for r in results:
        assert r.handle_error_mm is not None and r.handle_error_mm < LOCATE_LIMIT_MM, trial_line(r)
        assert r.can_error_mm is not None and r.can_error_mm < LOCATE_LIMIT_MM, trial_line(r)


def test_a_behaviour_on_the_right_hand_and_the_stick_on_the_left_run_in_the_same_ticks(results):
    """Eq. 5 for two points: in each trial the operation layer's status shows open_door's twist at rhand and the
    operator's streamed twist at lhand in the same ticks, for at least TWO_POINT_MIN_TICKS ticks."""
    for r in results:
        assert r.two_point_ticks >= TWO_POINT_MIN_TICKS, trial_line(r)
