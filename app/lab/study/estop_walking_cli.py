"""`hrp2-console study estop-walking`: the hard e-stop over the gait cycle's command line."""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from pathlib import Path

from app.lab.study.cli import add_backend_arguments, integer, number_list, run_or_exit_code, walk_names
from app.lab.study.estop_walking import HOLDS_S, WALKS

walk_list = walk_names(WALKS)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="hrp2-console study estop-walking",
        description="The hard e-stop while walking: the robot walking (goVelocity after 2.5 s standing) is e-stopped "
                    "at a phase of its gait cycle (from a right touchdown at least 2 s into the walk), held, "
                    "released and watched 6 s; each run stood or fell, and whether it froze on both feet. "
                    "Resumable: finished runs are kept in OUT/runs.jsonl and skipped when run again.")
    p.add_argument("--walks", type=walk_list, default=list(WALKS),
                   help=f"walks, comma-separated, from {', '.join(WALKS)} (0.2 m/s forward, 0.1 m/s back, 0.1 m/s "
                        "to the left, 0.1 m/s turning 10 deg/s; default all)")
    p.add_argument("--phases", type=integer(1, 200, "a number of phases"), default=16,
                   help="phases evenly over one gait cycle (default 16)")
    p.add_argument("--holds", type=number_list("s", 0.01, 60.0), default=list(HOLDS_S),
                   help=f"seconds from the press to the release, comma-separated, each in 0.01..60 (default "
                        f"{','.join(f'{h:g}' for h in HOLDS_S)})")
    add_backend_arguments(p)
    p.add_argument("--out", type=Path, default=Path("out/study/estop-walking"),
                   help="where the runs (runs.jsonl) and the summary go (default out/study/estop-walking)")
    return p


def main(argv: Sequence[str]) -> int:
    from app.lab.study.estop_walking import grid, run_estop, summary_markdown
    from app.lab.study.pool import PoolBackend
    from app.lab.study.ray_backend import RayBackend
    from app.lab.study.store import RunStore
    from app.lab.study.study import execute

    args = parser().parse_args(list(argv))
    specs = grid(args.walks, args.phases, args.holds)
    backend = (RayBackend(args.ray, fn=run_estop) if args.ray is not None
               else PoolBackend(args.workers or os.cpu_count() or 1, fn=run_estop))
    store = RunStore(args.out / "runs.jsonl")
    print(f"study estop-walking: {len(specs)} runs ({len(args.walks)} walks x {args.phases} phases x "
          f"{len(args.holds)} holds); on {backend.describe()}; {len(store)} runs already in {store.path}", flush=True)
    stats, code = run_or_exit_code("hrp2-console study estop-walking", store,
                                   lambda: execute("e-stop while walking", specs, backend, store))
    if code is not None:
        return code
    text = summary_markdown([(s, store.get(s.key())["result"]) for s in specs])
    text += f"\n{stats.runs} runs now, in {stats.wall_s:.0f} s of wall time ({stats.sim_s:.0f} s simulated)\n"
    (args.out / "summary.md").write_text(text)
    print(text, end="")
    return 0
