"""`hrp2-console study push-walking`: the push map's command line (issue 26)."""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from pathlib import Path

from app.lab.study.cli import (
    add_backend_arguments,
    integer,
    number_list,
    positive_seconds,
    run_or_exit_code,
    walk_names,
)
from app.lab.study.push_walking import WALKS, WATCH_S

walk_list = walk_names(WALKS, "; 'turn': 0.1 m/s turning 10 deg/s")


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="hrp2-console study push-walking",
        description="The push map: the robot walking (goVelocity after 2.5 s standing) is pushed on BODY for 0.1 s "
                    "at a phase of its gait cycle (from a right touchdown at least 2 s into the walk), with an "
                    "impulse in a direction of its frame, and watched; each run stood or fell, beside the LIP's "
                    "capturability of the push (0 or 1 step, or not). Resumable: finished runs are kept in "
                    "OUT/runs.jsonl and skipped when the command is run again.")
    p.add_argument("--speeds", type=walk_list, default=["0.1"],
                   help=f"walks, comma-separated, from {', '.join(WALKS)} ('turn': 0.1 m/s turning 10 deg/s; "
                        "default 0.1)")
    p.add_argument("--impulses", type=number_list("N s", 0.0, 200.0), default=[10.0, 20.0],
                   help="impulses [N s], comma-separated, each in 0..200 (default 10,20)")
    p.add_argument("--directions", type=integer(1, 72, "a number of directions"), default=8,
                   help="directions evenly around the robot from forward, counter-clockwise (default 8)")
    p.add_argument("--phases", type=integer(1, 200, "a number of phases"), default=16,
                   help="phases evenly over one gait cycle (default 16)")
    p.add_argument("--watch-s", type=positive_seconds, default=WATCH_S,
                   help=f"seconds watched after the push (0.5..600; default {WATCH_S:g})")
    add_backend_arguments(p)
    p.add_argument("--out", type=Path, default=Path("out/study/push-walking"),
                   help="where the runs (runs.jsonl) and the summary go (default out/study/push-walking)")
    p.add_argument("--img-dir", type=Path, default=None, help="where the heat maps go (default: OUT)")
    p.add_argument("--no-plots", action="store_true", help="no heat maps")
    return p


def main(argv: Sequence[str]) -> int:
    from app.lab.study.pool import PoolBackend
    from app.lab.study.push_map import hrp2_lip, map_paths, plot_push_map, run_map, summary_markdown
    from app.lab.study.push_walking import grid, run_push
    from app.lab.study.ray_backend import RayBackend
    from app.lab.study.store import RunStore

    args = parser().parse_args(list(argv))
    specs = grid(args.speeds, args.impulses, args.directions, args.phases, args.watch_s)
    backend = (RayBackend(args.ray, fn=run_push) if args.ray is not None
               else PoolBackend(args.workers or os.cpu_count() or 1, fn=run_push))
    paths = map_paths(args.out, args.speeds)
    if args.img_dir is not None:
        paths |= {k: args.img_dir / v.name for k, v in paths.items() if k.startswith("map ")}
    store = RunStore(paths["store"])
    print(f"study push-walking: {len(specs)} runs ({', '.join(args.speeds)} x {len(args.impulses)} impulses x "
          f"{args.directions} directions x {args.phases} phases); on {backend.describe()}; {len(store)} runs already "
          f"in {paths['store']}", flush=True)
    lip = hrp2_lip()
    done, code = run_or_exit_code("hrp2-console study push-walking", store,
                                  lambda: run_map(specs, backend, store, lip))
    if code is not None:
        return code
    cells, stats = done
    text = summary_markdown(cells, lip, stats)
    paths["summary"].parent.mkdir(parents=True, exist_ok=True)
    paths["summary"].write_text(text)
    if not args.no_plots:
        for w in args.speeds:
            plot_push_map(cells, w, paths[f"map {w}"], lip)
    print(text, end="")
    print("files: " + ", ".join(str(v) for k, v in paths.items() if not (k.startswith("map ") and args.no_plots)))
    return 0
