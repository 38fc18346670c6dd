"""Finished runs survive a restart; a torn last line (a study killed mid-write) is skipped and written past."""

import pytest

from app.lab.study.store import RunStore

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def record(key: str, verdict: str = "stood") -> dict:
    return {"key": key, "spec": {"x": 1}, "result": {"verdict": verdict}, "timing": {"wall_s": 1.0, "sim_s": 2.0}}


def test_runs_added_are_found_by_a_new_store_on_the_same_file(tmp_path):
    path = tmp_path / "sub" / "runs.jsonl"
    store = RunStore(path)
    store.add(record("a"))
    store.add(record("b", "fell"))
    again = RunStore(path)
    assert len(again) == 2 and "a" in again and again.get("b")["result"]["verdict"] == "fell"


def test_a_torn_last_line_is_skipped_and_the_next_run_starts_a_new_line(tmp_path):
    path = tmp_path / "runs.jsonl"
    store = RunStore(path)
    store.add(record("a"))
    with open(path, "a") as fh:
        fh.write('{"key": "b", "spec": {"x"')  # killed mid-write
    torn = RunStore(path)
    assert len(torn) == 1 and torn.skipped_lines == 1
    torn.add(record("c"))
    after = RunStore(path)
    assert set(after.records) == {"a", "c"} and after.skipped_lines == 1
