"""The campaign's markdown report: sessions, simulated time, actions by kind against the stated probabilities,
violations by invariant, falls by push, the findings."""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

from app.lab.campaign.checker import INVARIANTS, STAND_TOLERANCE_DEG
from app.lab.campaign.grammar import GAP_MEAN_S, PROBABILITIES, PUSH_ENVELOPE_NS
from app.lab.campaign.memory import GROWTH_BOUND_MB

NOT_CHECKED = (
    "disk (invariant 5) is bounded by construction, not measured: each console records into a temporary folder of "
    "its own that its retention rule bounds (20 files, 4 GB) and that goes with it; the campaign keeps this report, "
    "one JSON per violating session and the MCAP of its violating stretches",
    "the e-stop's 10 ms of control time (invariant 3) is not timed at `--speed max`: an answered e-stop is checked "
    "engaged on the first published state at or after the tick its answer names",
    "the late-tick bound (invariant 5) applies to paced consoles only; at `--speed max` nothing is paced",
)


def render(results: Sequence[Mapping[str, Any]], args: Mapping[str, Any], wall_s: float,
           findings: Sequence[str] = ()) -> str:
    """`results`: each session's SessionResult.to_dict(); `args`: the command's arguments."""
    counts: Counter = Counter()
    for r in results:
        counts.update(r["counts"])
    total = sum(counts.values()) or 1
    sim_s = sum(r["simulated_s"] for r in results)
    run_sim_s = args.get("run_simulated_s", sim_s)  # this run's sessions: the rest were kept from earlier runs
    resumed = int(args.get("resumed") or 0)
    by_inv: Counter = Counter(v["invariant"] for r in results for v in r["violations"])
    lines = [
        "# Random-operator campaign",
        "",
        f"`hrp2-console campaign {args.get('command', '')}`".rstrip(),
        "",
        f"- sessions: {len(results)} of {args.get('seconds')} s simulated each (seeds {args.get('seed')}.."
        f"{int(args.get('seed', 0)) + len(results) - 1})",
        f"- simulated: {sim_s:.0f} s ({sim_s / 3600:.3f} h, with the warm-ups and the end's checks); this run: "
        f"{len(results) - resumed} sessions, {run_sim_s:.0f} s simulated in {wall_s:.0f} s of wall time on "
        f"{args.get('workers')} worker(s) ({run_sim_s / max(wall_s, 1e-9):.1f}x real time)"
        + (f"; {resumed} kept from earlier runs (sessions.jsonl)" if resumed else ""),
        f"- sessions with a violation: {sum(1 for r in results if r['violations'])}",
        "",
        "## Actions by kind",
        "",
        f"One action every {GAP_MEAN_S:g} s simulated on average (exponential gaps); push envelope "
        f"{', '.join(f'{k} {v:g} N s' for k, v in PUSH_ENVELOPE_NS.items())}.",
        "",
        "| kind | stated probability | sent | share |",
        "|---|---|---|---|",
    ]
    for kind, p in PROBABILITIES.items():
        lines.append(f"| {kind} | {p:.2f} | {counts.get(kind, 0)} | {counts.get(kind, 0) / total:.2f} |")
    lines += ["", "## Violations by invariant", "", "| # | invariant | violations |", "|---|---|---|"]
    for n, rule in INVARIANTS.items():
        lines.append(f"| {n} | {rule} | {by_inv.get(n, 0)} |")
    beyond = [(r["seed"], b) for r in results for b in r.get("beyond_stands", ())]
    lines += ["", f"Invariant 6 compares every joint but the grippers with half-sitting within "
                  f"{STAND_TOLERANCE_DEG:g} deg. After a push beyond the envelope (above it, or any while the hard "
                  "e-stop holds the robot frozen) the invariants promise nothing, as for invariant 1's falls: a "
                  f"`stand` that did not bring the robot back then is listed here, not counted ({len(beyond)}):", ""]
    lines += [f"- seed {seed}, {b['time_s']:.2f} s: {b['detail']} (pushes beyond: "
              f"{', '.join(f'{j:.1f}/{e:g} N s at {t:.1f} s' for t, j, e in b['pushes'])})" for seed, b in beyond]
    lines += ["", "## Falls", "",
              "| seed | time [s] | pushes before (impulse [N s] / envelope) |", "|---|---|---|"]
    falls = [(r["seed"], f) for r in results for f in r["falls"]]
    for seed, f in falls:
        pushes = ", ".join(f"{j:.1f}/{e:g}" for _, j, e in f["pushes"]) or "none"
        lines.append(f"| {seed} | {f['time_s']:.2f} | {pushes} |")
    if not falls:
        lines.append("| - | - | no fall |")
    lines += ["", "## Memory", "", f"Resident memory of each console (its process and the robot process) after "
              f"each session; bound: {GROWTH_BOUND_MB:g} MB of growth from its first session to its last.", "",
              "| console | sessions | after the first [MB] | after the last [MB] | max [MB] |", "|---|---|---|---|---|"]
    consoles = sorted({(r.get("run", ""), r.get("worker", 0)) for r in results if r.get("rss_mb") is not None})
    runs = len({run for run, _ in consoles})  # a resumed campaign's earlier runs had consoles of their own
    for run, worker in consoles:
        rs = sorted((r for r in results if (r.get("run", ""), r.get("worker", 0)) == (run, worker)
                     and r.get("rss_mb") is not None), key=lambda r: r.get("order", 0))
        name = f"{run} / {worker}" if runs > 1 else worker
        lines.append(f"| {name} | {len(rs)} | {rs[0]['rss_mb']:.0f} | {rs[-1]['rss_mb']:.0f} | "
                     f"{max(r['rss_mb'] for r in rs):.0f} |")
    lines += ["", "## Findings", ""]
    for r in results:
        for v in r["violations"]:
            lines.append(f"- seed {r['seed']}, invariant {v['invariant']}, t = {v['time_s']:.2f} s: {v['detail']}")
    if not any(r["violations"] for r in results):
        lines.append("None.")
    if findings:
        lines += ["", "Saved: " + ", ".join(f"`{f}`" for f in findings)]
    lines += ["", "## Not checked", ""] + [f"- {n}" for n in NOT_CHECKED]
    return "\n".join(lines) + "\n"
