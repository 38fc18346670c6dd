"""The random operator in CI (issue 27): a short campaign with fixed seeds on real consoles at --speed max, through
the public API only. Its size: CI_SESSIONS sessions of CI_SECONDS s simulated on two consoles, the issue's size
(measured: 180-300 s of wall time on two cores, the sessions recorded).

Asserted: invariants 2-6 (the console's own promises: causes named, e-stops engaged, ok answers applied, no 5xx, the
robot process alive, no controller fault, the consoles' memory bounded; and `stand` back to half-sitting) in every
session. Printed, not asserted: invariant 1 (no fall without a push beyond the envelope), whose findings belong to the
walking controller and are still being found: these seeds ran clean twice on one day, and a CI run the same day then
found a fall with no push (seed 1007, 54.7 s into its session; replayed in process from its actions, it stands).
The sessions' timing against a console at --speed max is not deterministic: a finding is replayed from the
recording the campaign keeps (`hrp2-console campaign --seed 1000 --sessions 20 --seconds 60 --workers 2 --out DIR`),
and fixed with a regression test (docs/campaign.md lists them; tests/scenarios/test_campaign_findings.py holds
them)."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import pytest

from app.lab.campaign.checker import INVARIANTS
from app.lab.campaign.cli import main, run_campaign
from app.lab.campaign.grammar import PROBABILITIES

pytestmark = pytest.mark.slow

CI_SEED = 1000
CI_SESSIONS = 20
CI_SECONDS = 60.0
CI_WORKERS = 2
#: the invariants with open findings of the walking controller (see the module docstring): printed, not asserted
OPEN_INVARIANTS = (1,)


def test_a_fixed_seed_campaign_keeps_the_consoles_invariants():
    results = run_campaign(list(range(CI_SEED, CI_SEED + CI_SESSIONS)), CI_SECONDS, workers=CI_WORKERS)
    assert len(results) == CI_SESSIONS
    assert all(r["simulated_s"] >= CI_SECONDS for r in results)
    sent = {k for r in results for k in r["counts"]}
    assert len(sent) >= len(PROBABILITIES) - 3, sorted(set(PROBABILITIES) - sent)  # the grammar was exercised
    found = [(v["invariant"], f"seed {r['seed']}: invariant {v['invariant']} ({INVARIANTS[v['invariant']]}) at "
              f"{v['time_s']} s: {v['detail']}") for r in results for v in r["violations"]]
    print("\n".join(["open (walking controller):"] + [text for inv, text in found if inv in OPEN_INVARIANTS]))
    broken = [text for inv, text in found if inv not in OPEN_INVARIANTS]
    assert not broken, "\n".join(broken)


def test_the_command_writes_the_report_and_a_finding_per_violating_session_and_exits_non_zero_on_one(tmp_path):
    code = main(["--sessions", "1", "--seconds", "10", "--seed", str(CI_SEED), "--out", str(tmp_path)])
    report = (tmp_path / "report.md").read_text()
    assert "| stick | 0.14 |" in report and "## Violations by invariant" in report
    findings = sorted((tmp_path / "findings").glob("*.json")) if (tmp_path / "findings").exists() else []
    assert code == (1 if findings else 0)
    for f in findings:
        finding = json.loads(f.read_text())
        assert finding["seed"] == CI_SEED and finding["actions"] and finding["violations"][0]["invariant"] in INVARIANTS


def test_a_violating_stretch_is_kept_as_mcap_that_replays_bit_for_bit_and_a_clean_one_is_not_kept(tmp_path,
                                                                                                 monkeypatch):
    from app.lab.campaign.cli import save_findings
    from app.lab.campaign.grammar import catalogue_of
    from app.lab.campaign.session import Session
    from app.lab.console_process import Console
    from app.session.reader import read_session
    from app.session.replay import replay

    monkeypatch.setenv("HRP2_TEST_HOOKS", "1")  # POST /api/sim/fault
    with Console("--speed", "max", "--sessions-dir", str(tmp_path / "sessions")) as console:
        _, behaviors = console.request("GET", "/api/behaviors")
        catalogue = catalogue_of(behaviors)
        clean = Session(console.port, CI_SEED, 3.0, catalogue, actions=[], record=True).run()
        assert not clean.violations and not clean.recordings
        faulty = Session(console.port, CI_SEED, 6.0, catalogue, actions=[], record=True)

        def inject() -> None:  # once the session's own reset is done and its warm-up over (not by the wall clock)
            sim_s = lambda: console.request("GET", "/api/state")[1]["time"]  # noqa: E731
            while sim_s() > 1.0:
                time.sleep(0.02)
            while sim_s() < 4.0:
                time.sleep(0.02)
            # the campaign sends no fault: one injected here (the simulation's test door) violates invariant 5
            console.request("POST", "/api/sim/fault", {"kind": "layer", "layer": "st"})

        injected = threading.Thread(target=inject)
        injected.start()
        result = faulty.run()
        injected.join(timeout=30.0)
    assert [v.invariant for v in result.violations][:1] == [5] and "controller fault" in result.violations[0].detail
    [(name, data)] = result.recordings.items()
    saved = save_findings([{**result.to_dict(), "recordings": result.recordings}], tmp_path / "out")
    finding = json.loads(Path(saved[0]).read_text())
    assert finding["recordings"] == [name]
    replayed = replay(read_session(tmp_path / "out" / "findings" / name))
    assert replayed.identical, replayed.summary()
