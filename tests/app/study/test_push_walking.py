"""The push map's plumbing: its specs and keys, two short runs on the local pool (a push that the robot takes and
one that throws it over), the store resuming them, the counts against the LIP and the heat map."""

import math
import shutil
import tempfile
from pathlib import Path

import pytest

from app.lab.study.capturability import Lip
from app.lab.study.pool import PoolBackend
from app.lab.study.push_cli import parser, walk_list
from app.lab.study.push_map import Cell, cells_of, counts, plot_push_map, run_map, summary_markdown
from app.lab.study.push_walking import PushSpec, grid, run_push
from app.lab.study.store import RunStore
from tests.app.study.fakes import Counting

LIP = Lip(58.0, 0.8105)


def test_a_spec_round_trips_and_its_key_names_exactly_its_fields():
    s = PushSpec("0.1", 10.0, 45.0, 0.25, 6.0)
    assert PushSpec.from_dict(s.to_dict()) == s
    assert s.key() == PushSpec("0.1", 10.0, 45.0, 0.25, 6.0).key() != PushSpec("0.1", 10.0, 45.0, 0.3125).key()
    with pytest.raises(ValueError, match="unknown walk"):
        PushSpec("0.3", 10.0, 0.0, 0.0)
    with pytest.raises(ValueError):
        PushSpec("0.1", 10.0, 0.0, 1.0)


def test_the_grid_is_walks_by_impulses_by_directions_by_phases():
    specs = grid(["0.1", "turn"], [10.0, 20.0], 8, 16)
    assert len(specs) == 2 * 2 * 8 * 16 == len({s.key() for s in specs})
    assert sorted({s.direction_deg for s in specs}) == [45.0 * k for k in range(8)]
    assert sorted({s.phase for s in specs}) == [k / 16 for k in range(16)]


def test_the_command_line_names_the_walks_it_knows():
    assert walk_list("0.10, turn") == ["0.1", "turn"]
    a = parser().parse_args(["--speeds", "0.1,0.2", "--impulses", "10,20", "--phases", "16", "--workers", "1"])
    assert (a.speeds, a.impulses, a.directions, a.phases, a.workers) == (["0.1", "0.2"], [10.0, 20.0], 8, 16, 1)
    with pytest.raises(SystemExit):
        parser().parse_args(["--speeds", "0.5"])


def test_two_runs_on_the_pool_stand_and_fall_as_pushed_and_the_store_resumes_them():
    out = Path(tempfile.mkdtemp(prefix="push-map-"))
    try:
        gentle = PushSpec("0.1", 0.0, 0.0, 0.25, watch_s=1.0)
        # 60 N s to the right on the right foot: the left foot in the air cannot cross over to catch it
        hard = PushSpec("0.1", 60.0, 270.0, 0.25, watch_s=2.5)
        store = RunStore(out / "runs.jsonl")
        cells, stats = run_map([gentle, hard], PoolBackend(1, fn=run_push), store, LIP)
        assert stats.runs == 2 and len(store) == 2
        by = {c.spec: c for c in cells}
        # 1. no push: the walk goes on, no flag, no step of its own; pushed at a quarter cycle: right foot stance
        g = by[gentle].result
        assert g["outcome"] == "stood" and not g["flag"] and g["emergency_steps"] == 0
        assert g["support_at_push"] == "rleg" and g["cycle_measured_s"] == pytest.approx(2.0, abs=0.01)
        assert by[gentle].capture.steps == 0
        # 2. the flag rises, the robot falls, and the LIP says no single step could have caught it
        h = by[hard].result
        assert h["outcome"] == "fell" and h["flag"] and h["fall_after_push_s"] < 2.5
        assert not by[hard].capturable
        assert counts(cells).fell_not_capturable == 1 and counts(cells).fell_capturable == 0
        # 3. a second invocation finds both stored and runs none
        again = Counting()
        cells2, stats2 = run_map([gentle, hard], again, RunStore(out / "runs.jsonl"), LIP)
        assert again.asked == 0 and stats2.skipped == 2 and [c.result for c in cells2] == [c.result for c in cells]
    finally:
        shutil.rmtree(out, ignore_errors=True)


def fake_cells():
    store_like = []
    for s in grid(["0.1"], [10.0, 40.0], 8, 4):
        fell = s.impulse_ns > 20.0 and s.direction_deg in (0.0, 90.0)
        store_like.append((s, {"outcome": "fell" if fell else "stood", "fall_after_push_s": 1.0 if fell else None,
                               "peak_cp_error_m": 0.05, "flag": fell, "walking_stop": fell, "emergency_steps": 0,
                               "support_at_push": "both"}))
    return store_like


def test_the_counts_and_the_heat_map_of_a_map(tmp_path):
    class Store(dict):
        def get(self, key):
            return self[key]

    store = Store({s.key(): {"result": r} for s, r in fake_cells()})
    cells = cells_of([s for s, _ in fake_cells()], store, LIP)
    assert all(isinstance(c, Cell) for c in cells) and len(cells) == 64
    n = counts(cells)
    assert (n.runs, n.fell, n.stood) == (64, 8, 56)
    assert n.fell == n.fell_capturable + n.fell_not_capturable
    # 10 N s is within the ankles' reach at every phase and direction (the LIP's standing bound is 22-41 N s)
    assert all(c.capture.steps == 0 for c in cells if c.spec.impulse_ns == 10.0)
    text = summary_markdown(cells, LIP)
    assert "| 0.1 m/s | 40 | 32 | 24 | 8 |" in text
    path = plot_push_map(cells, "0.1", tmp_path / "map.png", LIP)
    assert path.stat().st_size > 10_000
    assert math.isclose(LIP.omega_1_s, 3.479, abs_tol=1e-3)
