"""`hrp2-console campaign`: seeded random-operator sessions on real consoles (one per worker), the checker's
findings saved as JSON, a markdown report; exits 1 on a violation. Each session is kept in `--out` the moment it
ends (sessions.jsonl, and its finding), so a soak interrupted (Ctrl-C, a crash, a machine wanted back) is resumed
by the same command, which runs only the seeds not yet kept."""

from __future__ import annotations

import argparse
import itertools
import json
import logging
import queue
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from app.cli_args import positive_int, positive_seconds, speed_or_max
from app.lab.campaign.grammar import Action, catalogue_of
from app.lab.campaign.memory import growth_violations, tree_rss_mb
from app.lab.campaign.report import render
from app.lab.campaign.session import Session, SessionResult
from app.lab.campaign.shrink import ddmin

log = logging.getLogger("hrp2-console.campaign")

SHRINK_TAIL_S = 8.0  # [s] simulated after a shrunk list's last action
SHRINK_TESTS = 32  # sessions a shrink may run at most


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="hrp2-console campaign",
                                description="Seeded random-operator sessions through the public API, with the "
                                            "invariants of issue 27 checked on every answer and state.")
    p.add_argument("--sessions", type=positive_int, default=20, help="how many sessions (default 20)")
    p.add_argument("--seconds", type=positive_seconds, default=60.0, help="simulated seconds per session")
    p.add_argument("--seed", type=int, default=0, help="the first session's seed; session i has seed + i")
    p.add_argument("--workers", type=positive_int, default=1, help="consoles run side by side (default 1)")
    p.add_argument("--speed", type=speed_or_max, default=None, help="the consoles' speed (default max)")
    p.add_argument("--shrink", action="store_true", help="reduce a failing session's actions (delta debugging)")
    p.add_argument("--no-record", action="store_true",
                   help="do not record the sessions (by default a stretch with a violation is kept as MCAP)")
    p.add_argument("--out", default="out/campaign", help="where report.md and findings/ go")
    return p


def run_campaign(seeds: Sequence[int], seconds: float, workers: int = 1, speed: float | None = None,
                 shrink: bool = False, record: bool = True,
                 on_result: Callable[[dict[str, Any]], None] | None = None) -> list[dict[str, Any]]:
    """Each seed's session on one of `workers` consoles; their SessionResult.to_dict() in seed order (with
    `shrunk`: the reduced failing action list, when asked). `on_result` is given each session's as it ends (from
    the worker's thread)."""
    from app.lab.console_process import Console

    todo: queue.Queue[int] = queue.Queue()
    for s in seeds:
        todo.put(s)
    results: dict[int, dict[str, Any]] = {}
    errors: list[BaseException] = []

    order = itertools.count()

    def worker(k: int) -> None:
        try:
            # the recordings in a folder of its own: the console's retention rule would prune the user's sessions
            with tempfile.TemporaryDirectory(prefix="hrp2-campaign-") as sessions, \
                    Console("--speed", "max" if speed is None else str(speed), "--sessions-dir", sessions) as console:
                _, behaviors = console.request("GET", "/api/behaviors")
                _, defaults = console.request("GET", "/api/params")
                catalogue = catalogue_of(behaviors)
                while True:
                    try:
                        seed = todo.get_nowait()
                    except queue.Empty:
                        return
                    r = Session(console.port, seed, seconds, catalogue, defaults=defaults, record=record).run()
                    d = {**r.to_dict(), "worker": k, "order": next(order), "rss_mb": tree_rss_mb(console.proc.pid),
                         "recordings": r.recordings}
                    if r.violations:
                        d["console_tail"] = "".join(console.lines[-40:])
                        if shrink:
                            d["shrunk"] = [a.to_dict() for a in _shrink(console.port, r, catalogue, defaults)]
                    results[seed] = d
                    if on_result is not None:
                        on_result(d)
                    log.info("seed %d: %d actions, %d violation(s), %.1f s wall", seed, len(r.actions),
                             len(r.violations), r.wall_s)
        except BaseException as exc:  # noqa: BLE001 - reported by the caller
            errors.append(exc)

    threads = [threading.Thread(target=worker, args=(k,), name=f"campaign-{k}")
               for k in range(min(workers, len(seeds)))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if errors:
        raise errors[0]
    for v in growth_violations(list(results.values())):  # invariant 5's memory bound, said on the last session
        results[v.pop("seed")]["violations"].append(v)
    return [results[s] for s in seeds]


def _shrink(port: int, r: SessionResult, catalogue, defaults) -> list[Action]:
    invariant = r.violations[0].invariant

    def fails(actions: list[Action]) -> bool:
        seconds = (actions[-1].at_s if actions else 0.0) + SHRINK_TAIL_S
        again = Session(port, r.seed, seconds, catalogue, actions=actions, defaults=defaults).run()
        return any(v.invariant == invariant for v in again.violations)

    return ddmin(r.actions, fails, max_tests=SHRINK_TESTS)


def save_finding(r: dict[str, Any], out: Path) -> str | None:
    """A violating session as JSON under out/findings (seed, actions, the violations with invariant and time),
    its recordings beside it; the recordings' bytes leave `r` (their names stay). None: no violation."""
    recordings = r.pop("recordings", None) or {}
    if not isinstance(recordings, dict):  # saved already (their names): the finding is written again, updated
        r["recordings"], recordings = recordings, {}
    if not r["violations"]:
        return None
    first = r["violations"][0]
    path = out / "findings" / f"seed-{r['seed']}-invariant-{first['invariant']}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    for name, data in recordings.items():  # `hrp2-console replay` replays each bit for bit
        (path.parent / name).write_bytes(data)
    r["recordings"] = sorted({*r.get("recordings", ()), *recordings})
    path.write_text(json.dumps(r, indent=1), encoding="utf-8")
    return str(path)


def save_findings(results: Sequence[dict[str, Any]], out: Path) -> list[str]:
    """save_finding for each of `results`: the paths written."""
    return [p for r in results if (p := save_finding(r, out)) is not None]


class SessionStore:
    """out/sessions.jsonl: one line per finished session, written as it ends (its finding saved first), each
    tagged with the run that made it and what makes sessions comparable (simulated seconds, speed). `done()`
    are the sessions of earlier runs to keep: the same seconds and speed."""

    def __init__(self, out: Path, seconds: float, speed: float | None) -> None:
        self.out, self.key = out, {"seconds": float(seconds), "speed": speed}
        self.path = out / "sessions.jsonl"
        self.run = f"{time.strftime('%Y%m%dT%H%M%S')}-{id(self) & 0xffff:04x}"
        self._lock = threading.Lock()
        self._violations: dict[int, int] = {}  # seed -> violations in its stored row

    def done(self) -> dict[int, dict[str, Any]]:
        kept: dict[int, dict[str, Any]] = {}
        if self.path.exists():
            for line in self.path.read_text(encoding="utf-8").splitlines():
                try:
                    r = json.loads(line)
                except ValueError:  # a line cut by a crash mid-write
                    continue
                if {k: r.get(k) for k in self.key} == self.key:
                    kept[int(r["seed"])] = r
        return kept

    def add(self, r: dict[str, Any]) -> None:
        with self._lock:
            self.out.mkdir(parents=True, exist_ok=True)
            save_finding(r, self.out)
            row = {**r, **self.key, "run": self.run}
            row.pop("trace", None)  # the finding keeps it; the store stays small over a soak
            with self.path.open("a", encoding="utf-8") as f:
                f.write(json.dumps(row) + "\n")
            self._violations[int(r["seed"])] = len(r["violations"])

    def amend(self, r: dict[str, Any]) -> None:
        """Store `r` again when it gained violations after it was added (invariant 5's memory bound, judged
        once every session has ended): its later line is the one `done()` keeps."""
        if len(r["violations"]) != self._violations.get(int(r["seed"])):
            self.add(r)


def main(argv: Sequence[str]) -> int:
    args = parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    seeds = [args.seed + i for i in range(args.sessions)]
    out = Path(args.out)
    store = SessionStore(out, args.seconds, args.speed)
    kept = {s: r for s, r in store.done().items() if s in seeds}
    if kept:
        print(f"campaign: {len(kept)} of {len(seeds)} sessions kept in {store.path} from earlier runs; "
              "running the rest")
    wall = time.monotonic()
    todo = [s for s in seeds if s not in kept]
    results = run_campaign(todo, args.seconds, args.workers, args.speed, args.shrink, record=not args.no_record,
                           on_result=store.add) if todo else []
    wall_s = time.monotonic() - wall
    for r in results:
        r["run"] = store.run
        store.amend(r)  # invariant 5's memory bound, judged after the sessions ended
    results = sorted([*kept.values(), *results], key=lambda r: r["seed"])
    findings = sorted(str(p) for p in (out / "findings").glob("seed-*.json")
                      if int(p.name.split("-")[1]) in seeds) if (out / "findings").exists() else []
    info = {**vars(args), "command": " ".join(argv), "resumed": len(kept),
            "run_simulated_s": sum(r["simulated_s"] for r in results if r["seed"] not in kept)}
    (out / "report.md").write_text(render(results, info, wall_s, findings), encoding="utf-8")
    violations = sum(len(r["violations"]) for r in results)
    print(f"campaign: {len(results)} sessions, {violations} violation(s), {wall_s:.0f} s wall; "
          f"report {out / 'report.md'}")
    return 1 if violations else 0
