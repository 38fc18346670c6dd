"""`hrp2-console study estop`: every option checked, the error naming the option and what is allowed."""

import pytest

from app.lab.study.cli import parser
from tests.app.test_cli import run


@pytest.mark.parametrize(("argv", "expected"), [
    (["--thresholds-mm", "40,250"], "--thresholds-mm: 250 is outside 5..200 mm"),
    (["--thresholds-mm", "40,x"], "--thresholds-mm: 'x' is not a number"),
    (["--t1-s", "nan"], "--t1-s: nan is outside 0..3 s"),
    (["--t2-s", "0"], "--t2-s: 0 is outside 0.05..3 s"),
    (["--experiments", "wall-push-forward,moon"], "--experiments: unknown experiment 'moon'; choose from "
                                                   "wall-push-forward, wall-push-left, valve, door"),
    (["--cases", "0"], "--cases: invalid value '0': expected a number of disturbance cases, an integer in 1..10000"),
    (["--case-grid", "12"], "--case-grid: invalid value '12': expected levels per disturbance, an integer in 2..9"),
    (["--workers", "0"], "--workers: invalid value '0': expected a number of processes, an integer in 1..64"),
    (["--duration-s", "-1"], "--duration-s: invalid value '-1': expected seconds in 0.5..600"),
    (["--workers", "2", "--ray", "auto"], "--ray: not allowed with argument --workers"),
    (["--cases", "3", "--case-grid", "3"], "--case-grid: not allowed with argument --cases"),
])
def test_a_bad_option_is_refused_naming_it_and_what_is_allowed(argv, expected, capsys):
    with pytest.raises(SystemExit) as exc:
        parser().parse_args(argv)
    assert exc.value.code == 2
    assert expected in capsys.readouterr().err


def test_the_defaults_are_the_readme_study():
    """The study docs/estop-study.md reports (it was in the README)."""
    args = parser().parse_args([])
    assert args.thresholds_mm == [20, 30, 40, 50, 60] and args.t1_s == [0.5, 1.0]
    assert args.t2_s == [0.25, 0.5, 1.0] and (args.cases, args.validate, args.seed) == (12, 30, 1)
    assert args.ray is None and args.workers is None  # None: every CPU


def test_the_same_seed_for_the_held_out_cases_is_refused_and_an_unknown_study_named():
    r = run("study", "estop", "--seed", "5", "--validation-seed", "5")
    assert r.returncode == 2 and "--validation-seed: must differ from --seed (5)" in r.stderr
    r = run("study", "gait")
    assert r.returncode == 2 and "expected a study name: estop" in r.stderr
