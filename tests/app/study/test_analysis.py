"""Per parameter set: falls rescued, harm, false alarms and the medians; the recommendation ranks false alarms
first, then standing; its bootstrap stability; the held-out validation's counts."""

import math

import pytest

from app.lab.study.analysis import collect, recommend, summarise, validate
from app.lab.study.space import Case, EstopParams
from app.lab.study.spec import RunSpec

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

LOW, MID, HIGH = EstopParams(0.02, 1.0, 0.5), EstopParams(0.04, 1.0, 0.5), EstopParams(0.06, 1.0, 0.5)
CASES = [Case.make("wall-push-forward", None, {"wall_gap_m": g}) for g in (-0.02, 0.0, 0.05)]
NOMINAL = [Case.make("door", "pull")]


def result(verdict="stood", flag=None, margin=None, peak=0.05, recovery=None):
    return {"verdict": verdict, "flag_time_s": flag, "edge_margin_at_flag_m": margin, "peak_cp_error_m": peak,
            "below_threshold_after_revert_s": recovery, "error": None if verdict != "error" else "IK"}


def results() -> dict:
    r = {}
    for th in (0.02, 0.04, 0.06):
        r[RunSpec.baseline(CASES[0], th).key()] = result("fell", 4.0)
        r[RunSpec.baseline(CASES[1], th).key()] = result("fell", 4.5)
        r[RunSpec.baseline(CASES[2], th).key()] = result("stood")
    # LOW: everything stands, early flags (but a false alarm on the nominal task)
    r[RunSpec(CASES[0], True, LOW).key()] = result("stood", 3.8, 0.09, 0.04, 0.1)
    r[RunSpec(CASES[1], True, LOW).key()] = result("stood", 4.2, 0.08, 0.04, 0.3)
    r[RunSpec(CASES[2], True, LOW).key()] = result("stood", 5.0, 0.09, 0.03, 0.2)
    r[RunSpec(NOMINAL[0], True, LOW).key()] = result("stood", 2.0, 0.1)
    # MID: both falls rescued, no flag on the third
    r[RunSpec(CASES[0], True, MID).key()] = result("stood", 4.0, 0.05, 0.06, 0.0)
    r[RunSpec(CASES[1], True, MID).key()] = result("stood", 4.4, 0.05, 0.07, None)
    r[RunSpec(CASES[2], True, MID).key()] = result("stood")
    r[RunSpec(NOMINAL[0], True, MID).key()] = result("stood")
    # HIGH: one rescued, one still falls, and it harms the third
    r[RunSpec(CASES[0], True, HIGH).key()] = result("stood", 4.2, 0.02, 0.09, 0.5)
    r[RunSpec(CASES[1], True, HIGH).key()] = result("fell", 4.6, 0.01, 0.8)
    r[RunSpec(CASES[2], True, HIGH).key()] = result("fell", 5.5, 0.03, 0.7)
    r[RunSpec(NOMINAL[0], True, HIGH).key()] = result("stood")
    return r


def outcomes():
    r = results()
    return collect([LOW, MID, HIGH], CASES, NOMINAL, lambda spec: r.get(spec.key()), None)


def test_each_parameter_set_is_summarised_over_the_cases():
    low, mid, high = summarise(outcomes())
    assert (low.cases, low.fell_without, low.rescued, low.harmed, low.stood_with) == (3, 2, 2, 0, 3)
    assert low.false_alarms == 1
    assert (mid.rescued, mid.harmed, mid.false_alarms, mid.unrecovered) == (2, 0, 0, 1)
    assert mid.margin_at_flag_mm == 50.0 and mid.recovery_s == 0.0 and mid.peak_error_mm == 60.0
    assert (high.rescued, high.harmed, high.stood_with) == (1, 1, 1)
    assert high.rescue_share == 0.5 and high.margin_at_flag_mm == 20.0


def test_the_recommendation_has_no_false_alarm_and_the_most_standing_and_resampling_keeps_it():
    rec = recommend(outcomes(), resamples=200, seed=3)
    assert rec.summary.params == MID  # LOW stands everywhere too, but raises the flag on the undisturbed door
    assert rec.chosen_share > 0.5 and rec.threshold_share >= rec.chosen_share
    assert rec.rescue_interval[1] == 1.0 and 0.0 < rec.rescue_interval[0] < 1.0


def test_a_nominal_task_that_failed_counts_as_a_false_alarm():
    r = results()
    r[RunSpec(NOMINAL[0], True, MID).key()] = result("error")  # the flag stopped the walk: the plan failed
    mid = summarise(collect([MID], CASES, NOMINAL, lambda spec: r.get(spec.key()), None))[0]
    assert mid.false_alarms == 1


def test_a_failed_run_leaves_its_case_out():
    r = results()
    r[RunSpec(CASES[0], True, MID).key()] = result("error")
    mid = summarise(collect([MID], CASES, NOMINAL, lambda spec: r.get(spec.key()), None))[0]
    assert (mid.cases, mid.fell_without, mid.rescued) == (2, 1, 1)


def test_the_validation_counts_falls_without_and_what_stood_with():
    r = results()
    v = validate(HIGH, CASES, lambda spec: r.get(spec.key()), None)
    assert (v.cases, v.errors, v.fell_without, v.rescued, v.harmed, v.flagged_standing) == (3, 0, 2, 1, 1, 1)
    assert v.rescue_share == 0.5 and not math.isnan(v.rescue_interval[0])
