"""What the seeded-trial experiments (chair, trash) share on the command line: one trial or N seeded ones, run in
the experiments' worker pool (expo.run_trials), printed as they finish and summed up."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

from app.lab.experiments.expo import run_trials


def seeded_parser(prog: str, description: str, one: str, metavar: tuple[str, str, str], one_help: str
                  ) -> argparse.ArgumentParser:
    """The options: `--ONE A B C` (one trial), or --trials/--seed/--workers; --verbose, --png."""
    p = argparse.ArgumentParser(prog=prog, description=description)
    p.add_argument(f"--{one}", nargs=3, type=float, metavar=metavar, help=one_help)
    p.add_argument("--trials", type=int, default=10, help="seeded trials (default 10)")
    p.add_argument("--seed", type=int, default=8, help="seed of the placements")
    p.add_argument("--workers", type=int, default=1, choices=range(1, 65), metavar="N",
                   help="trials run in N processes at once (1-64; the results do not depend on it)")
    p.add_argument("--verbose", action="store_true", help="print each step (one trial)")
    p.add_argument("--png", type=Path, help="write the trials' top view here")
    return p


def run_seeded(args: argparse.Namespace, placements: Callable, run_trial: Callable, summary_table: Callable
               ) -> list:
    """args.trials trials of placements(args.trials, args.seed) in args.workers processes, each printed as it
    ends; the summary table printed; the results in trial order."""
    results = []
    for done, r in enumerate(run_trials(placements(args.trials, args.seed), args.workers, run=run_trial), start=1):
        results.append(r)
        print(f"[{done}/{args.trials}] trial {r.trial}: {r.verdict} ({r.sim_time_s:.0f} s sim, "
              f"{r.wall_time_s:.0f} s wall)", flush=True)
    results.sort(key=lambda r: r.trial)
    print(summary_table(results))
    return results


def one_trial(run: Callable, verbose: bool, summary_table: Callable) -> int:
    """`run(progress=...)` once (each step printed when `verbose`), its table and verdict printed; the exit code."""
    r = run(progress=(lambda m: print(m, flush=True)) if verbose else None)
    print(summary_table([r]))
    print(r.verdict)
    return 0 if r.succeeded else 1
