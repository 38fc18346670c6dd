"""A study run's key names exactly what the run does."""

import pytest

from app.lab.study.space import Case, EstopParams
from app.lab.study.spec import SETTLE_S, RunSpec

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

CASE = Case.make("wall-push-left", None, {"wall_gap_m": -0.01})


def test_the_key_changes_with_everything_the_run_does_and_survives_a_round_trip():
    spec = RunSpec(CASE, True, EstopParams(0.04, 1.0, 0.5), 5.0)
    assert RunSpec.from_dict(spec.to_dict()) == spec and RunSpec.from_dict(spec.to_dict()).key() == spec.key()
    others = [RunSpec(CASE, False, spec.params, 5.0), RunSpec(CASE, True, EstopParams(0.05, 1.0, 0.5), 5.0),
              RunSpec(CASE, True, EstopParams(0.04, 0.5, 0.5), 5.0), RunSpec(CASE, True, spec.params, None),
              RunSpec(Case.make("wall-push-left", None, {"wall_gap_m": -0.02}), True, spec.params, 5.0)]
    assert len({spec.key(), *(o.key() for o in others)}) == 6


def test_a_run_without_the_emergency_stopper_is_one_per_threshold():
    assert RunSpec.baseline(CASE, 0.04).key() == RunSpec(CASE, False, EstopParams(0.04, 1.0, 0.5)).key()
    assert RunSpec.baseline(CASE, 0.04).key() != RunSpec.baseline(CASE, 0.05).key()


def test_the_expected_simulated_time_is_the_settling_and_the_experiment():
    assert RunSpec.baseline(CASE, 0.04).expected_sim_s() == SETTLE_S + 10.0
    assert RunSpec.baseline(CASE, 0.04, 3.0).expected_sim_s() == SETTLE_S + 3.0
