"""The sessions folder's retention rule: the oldest session files go when the folder holds more than the count or
the bytes allowed; the one being recorded stays (and counts); files that are not sessions are never touched."""

import os

import pytest

from app.session.files import prune_sessions

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def _session(folder, name: str, size: int, age_s: float):
    path = folder / name
    path.write_bytes(b"x" * size)
    t = 1_800_000_000 - age_s
    os.utime(path, (t, t))
    return path


def test_the_oldest_sessions_go_when_the_folder_holds_more_than_the_count(tmp_path):
    for i in range(5):
        _session(tmp_path, f"s{i}.mcap", 10, age_s=100 - i)  # s0 is the oldest
    assert prune_sessions(tmp_path, max_count=3, max_bytes=10**9) == ["s0.mcap", "s1.mcap"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s2.mcap", "s3.mcap", "s4.mcap"]
    assert prune_sessions(tmp_path, max_count=3, max_bytes=10**9) == []  # within the rule: nothing goes


def test_the_oldest_sessions_go_until_the_folder_holds_at_most_the_bytes(tmp_path):
    _session(tmp_path, "old.mcap", 600, age_s=30)
    _session(tmp_path, "mid.mcap", 300, age_s=20)
    _session(tmp_path, "new.mcap", 300, age_s=10)
    assert prune_sessions(tmp_path, max_count=10, max_bytes=700) == ["old.mcap"]  # 1200 -> 600 bytes
    assert prune_sessions(tmp_path, max_count=10, max_bytes=599) == ["mid.mcap"]
    assert [p.name for p in tmp_path.iterdir()] == ["new.mcap"]


def test_the_session_being_recorded_is_never_removed_but_counts(tmp_path):
    recording = _session(tmp_path, "recording.mcap", 1000, age_s=50)  # the oldest, and alone over the bytes
    _session(tmp_path, "a.mcap", 10, age_s=40)
    _session(tmp_path, "b.mcap", 10, age_s=30)
    assert prune_sessions(tmp_path, max_count=2, max_bytes=100, keep=[recording]) == ["a.mcap", "b.mcap"]
    assert recording.exists()


def test_files_that_are_not_sessions_are_never_removed(tmp_path):
    _session(tmp_path, "notes.txt", 10, age_s=90)
    _session(tmp_path, "x y.mcap", 10, age_s=80)  # not a session name
    (tmp_path / "sub.mcap").mkdir()
    _session(tmp_path, "s.mcap", 10, age_s=10)
    assert prune_sessions(tmp_path, max_count=1, max_bytes=0) == ["s.mcap"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt", "sub.mcap", "x y.mcap"]
    assert prune_sessions(tmp_path / "missing", max_count=1, max_bytes=0) == []


def test_a_recording_not_on_disk_yet_counts(tmp_path):
    _session(tmp_path, "a.mcap", 10, age_s=20)
    _session(tmp_path, "b.mcap", 10, age_s=10)
    assert prune_sessions(tmp_path, max_count=2, max_bytes=100, keep=[tmp_path / "new.mcap"]) == ["a.mcap"]
