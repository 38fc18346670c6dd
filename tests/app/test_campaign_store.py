"""A soak interrupted is resumed (issue 27: 500 sessions of 2 minutes are hours of a machine): each session is kept
in --out the moment it ends, and the same command runs only the seeds not yet kept. The consoles are replaced by a
stand-in run_campaign here (the sessions' own behaviour is tests/app/test_campaign.py's)."""

from __future__ import annotations

import json

import pytest

from app.lab.campaign import cli


def result(seed: int, violations=()) -> dict:
    return {"seed": seed, "seconds": 10.0, "actions": [{"kind": "stick", "at_s": 1.0}], "counts": {"stick": 1},
            "violations": list(violations), "simulated_s": 12.0, "wall_s": 3.0, "falls": [], "pushes": [],
            "trace": [{"t": 0}], "worker": 0, "order": seed, "rss_mb": 700.0,
            "recordings": {f"campaign-{seed}-0.mcap": b"mcap"} if violations else {}}


class Interrupted(Exception):
    pass


def stand_in(ran: list[int], stop_after: int | None = None, memory_violation_on: int | None = None):
    def run_campaign(seeds, seconds, workers=1, speed=None, shrink=False, record=True, on_result=None):
        out = []
        for s in seeds:
            if stop_after is not None and len(ran) == stop_after:
                raise Interrupted  # the machine wanted back mid-soak
            r = result(s, [{"invariant": 1, "time_s": 5.0, "detail": "fell"}] if s % 3 == 0 else [])
            ran.append(s)
            on_result(r)
            out.append(r)
        if memory_violation_on is not None:  # judged once every session has ended, as run_campaign does
            next(r for r in out if r["seed"] == memory_violation_on)["violations"].append(
                {"invariant": 5, "time_s": 0.0, "detail": "console 0's memory grew 200 MB"})
        return out
    return run_campaign


def test_an_interrupted_campaign_keeps_what_ended_and_the_same_command_runs_only_the_rest(tmp_path, monkeypatch):
    args = ["--sessions", "5", "--seconds", "10", "--seed", "100", "--out", str(tmp_path)]
    ran: list[int] = []
    monkeypatch.setattr(cli, "run_campaign", stand_in(ran, stop_after=3))
    with pytest.raises(Interrupted):
        cli.main(args)
    assert ran == [100, 101, 102]
    rows = [json.loads(line) for line in (tmp_path / "sessions.jsonl").read_text().splitlines()]
    assert [r["seed"] for r in rows] == [100, 101, 102] and all("trace" not in r for r in rows)
    finding = json.loads((tmp_path / "findings" / "seed-102-invariant-1.json").read_text())
    assert finding["trace"] and finding["recordings"] == ["campaign-102-0.mcap"]
    assert (tmp_path / "findings" / "campaign-102-0.mcap").read_bytes() == b"mcap"

    ran.clear()
    monkeypatch.setattr(cli, "run_campaign", stand_in(ran, memory_violation_on=104))
    assert cli.main(args) == 1  # seed 102's fall (kept) and 104's memory
    assert ran == [103, 104]
    report = (tmp_path / "report.md").read_text()
    assert "sessions: 5 of 10.0 s" in report and "2 sessions, 24 s simulated" in report
    assert "3 kept from earlier runs" in report
    assert "seed 102, invariant 1" in report and "seed 104, invariant 5" in report
    kept = cli.SessionStore(tmp_path, 10.0, None).done()
    assert sorted(kept) == [100, 101, 102, 103, 104] and len(kept[104]["violations"]) == 1  # the amended line

    ran.clear()  # everything kept: nothing runs, the report is written again
    assert cli.main(args) == 1 and ran == []


def test_sessions_of_another_length_or_speed_are_not_taken_for_these(tmp_path, monkeypatch):
    ran: list[int] = []
    monkeypatch.setattr(cli, "run_campaign", stand_in(ran))
    cli.main(["--sessions", "2", "--seconds", "10", "--seed", "100", "--out", str(tmp_path)])
    cli.main(["--sessions", "2", "--seconds", "20", "--seed", "100", "--out", str(tmp_path)])
    cli.main(["--sessions", "2", "--seconds", "10", "--speed", "2", "--seed", "100", "--out", str(tmp_path)])
    assert ran == [100, 101] * 3
