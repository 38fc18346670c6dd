"""What a study varies: parameter grids and samples, disturbance cases (seeded, complete, in range), their split."""

import pytest

from app.lab.experiments import EXPERIMENTS
from app.lab.study.space import (
    Case,
    EstopParams,
    allocation,
    case_grid,
    case_sample,
    fixed_cases,
    nominal_cases,
    param_grid,
    param_sample,
)

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

ALL = ("wall-push-forward", "wall-push-left", "valve", "door")


def test_the_grid_has_every_combination_once_threshold_slowest():
    grid = param_grid([0.03, 0.04], [1.0], [0.25, 0.5, 0.5])
    assert grid == [EstopParams(0.03, 1.0, 0.25), EstopParams(0.03, 1.0, 0.5), EstopParams(0.04, 1.0, 0.25),
                    EstopParams(0.04, 1.0, 0.5)]
    assert grid[0].layer_params() == {"st": {"cp_threshold_m": 0.03}, "es": {"t1_s": 1.0, "t2_s": 0.25}}


def test_a_parameter_sample_is_seeded_distinct_rounded_and_in_range():
    a = param_sample(20, 7, (0.02, 0.07), (0.5, 1.5), (0.25, 1.0))
    assert a == param_sample(20, 7, (0.02, 0.07), (0.5, 1.5), (0.25, 1.0))
    assert a != param_sample(20, 8, (0.02, 0.07), (0.5, 1.5), (0.25, 1.0))
    assert len(set(a)) == 20
    for p in a:
        assert 0.02 <= p.threshold_m <= 0.07 and 0.5 <= p.t1_s <= 1.5 and 0.25 <= p.t2_s <= 1.0
        assert round(p.t1_s / 0.05, 6).is_integer() and round(p.threshold_m * 1e3, 6).is_integer()
    with pytest.raises(ValueError, match="fewer than 5"):
        param_sample(5, 0, (0.04, 0.04), (1.0, 1.0), (0.5, 0.5))


def test_cases_are_spread_in_proportion_to_the_declared_disturbances():
    assert allocation(12, ALL) == {"wall-push-forward": 5, "wall-push-left": 3, "valve": 4}  # 4 : 2 : 3
    assert sum(allocation(7, ALL).values()) == 7
    assert allocation(3, ("door",)) == {}


def test_a_case_sample_is_seeded_complete_and_in_range():
    cases = case_sample(12, 1, ALL)
    assert cases == case_sample(12, 1, ALL) and cases != case_sample(12, 2, ALL)
    assert len(set(cases)) == 12
    for c in cases:
        declared = EXPERIMENTS[c.experiment].disturbances
        assert [k for k, _ in c.disturbance] == list(declared)
        assert all(declared[k].low <= v <= declared[k].high for k, v in c.disturbance)
    assert {c.variant for c in cases if c.experiment == "valve"} == {"undisturbed"}  # the offsets are all of it


def test_equal_cases_are_equal_however_they_were_written():
    a = Case.make("wall-push-forward", None, {"wall_gap_m": 0.02})
    b = Case.make("wall-push-forward", "default", {"push_yaw_deg": 0.0, "wall_gap_m": 0.02})
    assert a == b and hash(a) == hash(b)
    assert a.label() == "wall-push-forward [default] wall_gap_m 0.02"
    with pytest.raises(ValueError, match="available: default"):
        Case.make("wall-push-forward", "sideways")


def test_the_grid_varies_one_disturbance_at_a_time_and_the_door_has_one_case():
    grid = case_grid(3, ("wall-push-left", "door"))
    defaults = EXPERIMENTS["wall-push-left"].disturbance()
    for c in grid:
        changed = [k for k, v in c.disturbance if v != defaults.get(k)]
        assert len(changed) <= 1
    assert len([c for c in grid if c.experiment == "wall-push-left"]) == 1 + 3 + 3  # the default, each at 3 levels
    assert [c for c in grid if c.experiment == "door"] == fixed_cases(("door",)) == [Case("door", "push-plan", ())]
    assert [c.variant for c in nominal_cases(ALL)] == ["undisturbed", "pull"]
