"""The e-stop-while-walking study's plumbing: its specs and keys, the grid, the command line's checks and the summary
table (its runs are tests/scenarios/test_estop_walking.py's)."""

import pytest

from app.lab.study.estop_walking import EstopSpec, grid, summary_markdown
from app.lab.study.estop_walking_cli import parser

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_a_spec_round_trips_and_its_key_names_exactly_its_fields():
    s = EstopSpec("side", 0.25, 1.25)
    assert EstopSpec.from_dict(s.to_dict()) == s
    assert s.key() == EstopSpec("side", 0.25, 1.25).key() != EstopSpec("side", 0.25, 3.0).key()
    with pytest.raises(ValueError, match="unknown walk"):
        EstopSpec("sideways", 0.0, 1.0)
    for phase, hold in ((1.0, 1.0), (-0.1, 1.0), (0.0, 0.0)):
        with pytest.raises(ValueError):
            EstopSpec("0.2", phase, hold)


def test_the_grid_is_walks_by_phases_by_holds():
    specs = grid(["0.2", "side"], 16, [0.3, 3.0])
    assert len(specs) == 2 * 16 * 2 == len({s.key() for s in specs})
    assert sorted({s.phase for s in specs}) == [k / 16 for k in range(16)]


@pytest.mark.parametrize(("args", "named"), [(["--walks", "0.3"], "--walks"), (["--phases", "0"], "--phases"),
                                             (["--holds", "0"], "--holds"), (["--holds", "x"], "--holds")])
def test_the_command_line_refuses_bad_values_naming_the_option(args, named, capsys):
    with pytest.raises(SystemExit) as exc:
        parser().parse_args(args)
    assert exc.value.code == 2 and named in capsys.readouterr().err


def test_the_summary_counts_each_walk_and_hold_and_names_the_falls():
    def result(outcome, frozen, peak_m):
        return {"outcome": outcome, "fall_after_release_s": 1.5 if outcome == "fell" else None,
                "support_at_press": "lleg", "frozen_after_s": 0.35, "support_frozen": frozen,
                "cp_error_at_release_m": 0.01, "peak_cp_error_m": peak_m, "flag": peak_m > 0.04, "error": None}

    rows = [(EstopSpec("side", 0.0, 3.0), result("stood", "both", 0.004)),
            (EstopSpec("side", 0.5, 3.0), result("fell", "lleg", 0.8))]
    text = summary_markdown(rows)
    assert "| side | 3 | 2 | 1 | 1 | 1 | 10.0 | 800.0 | 0 |" in text
    assert "fell: 1 of 2\n- side, phase 0.5, hold 3 s (pressed in lleg): 1.50 s after the release" in text
