"""`hrp2-console study estop`: the e-stop parameter study's command line (every option checked, errors name the
option and what is allowed)."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from app.lab.study.space import (
    STUDY_VARIANTS,
    T1_LIMITS_S,
    T2_LIMITS_S,
    THRESHOLD_LIMITS_M,
    case_grid,
    case_sample,
    fixed_cases,
    nominal_cases,
    param_grid,
    param_sample,
)

MAX_CASES = 10_000
MAX_PARAM_SETS = 10_000


def number_list(unit: str, low: float, high: float):
    """An argparse type: comma-separated numbers, each finite and in [low, high] (in `unit`)."""

    def parse(text: str) -> list[float]:
        values = []
        for item in text.split(","):
            try:
                v = float(item)
            except ValueError:
                raise argparse.ArgumentTypeError(f"{item.strip()!r} is not a number; expected comma-separated "
                                                 f"numbers in {low:g}..{high:g} {unit}") from None
            if not (math.isfinite(v) and low <= v <= high):
                raise argparse.ArgumentTypeError(f"{item.strip()} is outside {low:g}..{high:g} {unit}")
            values.append(v)
        return list(dict.fromkeys(values))

    return parse


def integer(low: int, high: int, what: str):
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            v = low - 1
        if not low <= v <= high:
            raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected {what}, an integer in {low}..{high}")
        return v

    return parse


def experiment_list(text: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    valid = tuple(STUDY_VARIANTS)
    bad = [n for n in names if n not in valid]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"unknown experiment {bad[0] if bad else text!r}; choose from "
                                         f"{', '.join(valid)} (comma-separated)")
    return list(dict.fromkeys(names))


def positive_seconds(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and 0.5 <= v <= 600.0):
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected seconds in 0.5..600")
    return v


def walk_names(known, hint: str = ""):
    """An argparse type: comma-separated names of walks in `known` ("0.10" reads as "0.1"), each once."""

    def parse(text: str) -> list[str]:
        names = [n.strip() for n in text.split(",") if n.strip()]
        names = [f"{float(n):g}" if n.replace(".", "", 1).isdigit() else n for n in names]
        bad = [n for n in names if n not in known]
        if bad or not names:
            raise argparse.ArgumentTypeError(f"unknown walk {bad[0] if bad else text!r}; choose from "
                                             f"{', '.join(known)} (comma-separated{hint})")
        return list(dict.fromkeys(names))

    return parse


def run_or_exit_code(prog: str, store, work):
    """`work()` for a study's command line: (its value, None), or (None, the exit code) once it has said why the
    study stopped: no Ray cluster (2), or Ctrl-C (130: the finished runs stay in `store`, a RunStore, and the same
    command goes on from there)."""
    from app.lab.study.ray_backend import RayUnavailable

    try:
        return work(), None
    except RayUnavailable as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return None, 2
    except KeyboardInterrupt:
        print(f"\n{prog}: interrupted; {len(store)} finished runs are kept in {store.path}: the same command goes "
              "on from there", file=sys.stderr)
        return None, 130


def add_backend_arguments(p: argparse.ArgumentParser) -> None:
    """--workers (a local process pool) or --ray (a cluster): where a study's runs go."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=integer(1, 64, "a number of processes"), default=None,
                       help=f"runs at once in a local process pool (1-64; default: the CPUs, {os.cpu_count()})")
    where.add_argument("--ray", metavar="ADDRESS", default=None,
                       help="run on a Ray cluster instead (HOST:PORT, ray://HOST:10001, auto; 'local': a private one "
                            "on this machine); needs the ray extra: pip install -e '.[ray]'")


def parser() -> argparse.ArgumentParser:
    th_lo, th_hi = (v * 1e3 for v in THRESHOLD_LIMITS_M)
    p = argparse.ArgumentParser(
        prog="hrp2-console study estop",
        description="The e-stop parameter study: the [MLC] IV-C experiments (wall pushes, valve, door) over "
                    "(threshold, T1, T2) x disturbance cases, with and without the EmergencyStopper; a table, "
                    "heatmaps, the recommended parameters and their held-out validation. Resumable: finished runs "
                    "are kept in OUT/runs.jsonl and skipped when the command is run again.")
    p.add_argument("--thresholds-mm", type=number_list("mm", th_lo, th_hi),
                   default=[20.0, 30.0, 40.0, 50.0, 60.0],
                   help=f"flag thresholds [mm], comma-separated, each in {th_lo:g}..{th_hi:g} (default 20,...,60)")
    p.add_argument("--t1-s", type=number_list("s", *T1_LIMITS_S), default=[0.5, 1.0],
                   help=f"T1 values [s], each in {T1_LIMITS_S[0]:g}..{T1_LIMITS_S[1]:g} (default 0.5,1)")
    p.add_argument("--t2-s", type=number_list("s", *T2_LIMITS_S), default=[0.25, 0.5, 1.0],
                   help=f"T2 values [s], each in {T2_LIMITS_S[0]:g}..{T2_LIMITS_S[1]:g} (default 0.25,0.5,1)")
    p.add_argument("--param-samples", type=integer(0, MAX_PARAM_SETS, "a number of parameter sets"), default=0,
                   metavar="N", help="N random (threshold, T1, T2) within the lists' smallest and largest values "
                                     "instead of their grid (0, the default: the grid)")
    p.add_argument("--experiments", type=experiment_list, default=list(STUDY_VARIANTS),
                   help=f"comma-separated, from {', '.join(STUDY_VARIANTS)} (default: all)")
    cases = p.add_mutually_exclusive_group()
    cases.add_argument("--cases", type=integer(1, MAX_CASES, "a number of disturbance cases"), default=12, metavar="N",
                       help="N random tuning cases, every declared disturbance uniform in its range, spread over the "
                            "experiments in proportion to how many disturbances each declares; plus one case of each "
                            "experiment without any (the door's pushing plan) (default 12)")
    cases.add_argument("--case-grid", type=integer(2, 9, "levels per disturbance"), default=None, metavar="LEVELS",
                       help="instead: one factor at a time, each disturbance at LEVELS values of its range (2-9)")
    p.add_argument("--seed", type=integer(0, 2**31 - 1, "a seed"), default=1, help="seed of the tuning cases and "
                   "parameter samples (default 1)")
    p.add_argument("--validate", type=integer(0, MAX_CASES, "a number of held-out cases"), default=30, metavar="N",
                   help="N random held-out cases (not tuned on) for the recommended set (default 30; 0: none)")
    p.add_argument("--validation-seed", type=integer(0, 2**31 - 1, "a seed"), default=None,
                   help="seed of the held-out cases; must differ from --seed (default: --seed + 1)")
    p.add_argument("--duration-s", type=positive_seconds, default=None,
                   help="end every experiment after this many seconds (0.5..600; default: each one's own length)")
    add_backend_arguments(p)
    p.add_argument("--bootstrap", type=integer(0, 100_000, "a number of resamples"), default=1000,
                   help="bootstrap resamples behind the recommendation's confidence (default 1000)")
    p.add_argument("--out", type=Path, default=Path("out/study/estop"),
                   help="where the runs (runs.jsonl), the tables and the heatmap go (default out/study/estop)")
    p.add_argument("--no-plots", action="store_true", help="no heatmap")
    return p


def main(argv: Sequence[str]) -> int:
    from app.lab.study.analysis import summarise
    from app.lab.study.heatmap import plot_heatmaps
    from app.lab.study.pool import PoolBackend
    from app.lab.study.ray_backend import RayBackend
    from app.lab.study.report import summary_markdown, write_params_csv, write_runs_csv
    from app.lab.study.store import RunStore
    from app.lab.study.study import StudyConfig, run_study, study_paths

    p = parser()
    args = p.parse_args(list(argv))
    validation_seed = args.seed + 1 if args.validation_seed is None else args.validation_seed
    if validation_seed == args.seed:
        p.error(f"argument --validation-seed: must differ from --seed ({args.seed}): the held-out cases must not be "
                "the tuning cases")
    if args.param_samples:
        thresholds_m = [t / 1e3 for t in args.thresholds_mm]
        params = param_sample(args.param_samples, args.seed, (min(thresholds_m), max(thresholds_m)),
                              (min(args.t1_s), max(args.t1_s)), (min(args.t2_s), max(args.t2_s)))
    else:
        params = param_grid([t / 1e3 for t in args.thresholds_mm], args.t1_s, args.t2_s)
    if args.case_grid is not None:
        cases = case_grid(args.case_grid, args.experiments)
    else:
        cases = case_sample(args.cases, args.seed, args.experiments) + fixed_cases(args.experiments)
    held_out = [c for c in case_sample(args.validate, validation_seed, args.experiments) if c not in set(cases)]
    config = StudyConfig(params, cases, held_out, nominal_cases(args.experiments), args.duration_s, args.bootstrap,
                         args.seed)
    backend = RayBackend(args.ray) if args.ray is not None else PoolBackend(args.workers or os.cpu_count() or 1)
    paths = study_paths(args.out)
    store = RunStore(paths["store"])
    print(f"study estop: {len(params)} parameter sets x {len(cases)} cases ({', '.join(args.experiments)}), "
          f"{len(held_out)} held-out cases; on {backend.describe()}; {len(store)} runs already in {paths['store']}",
          flush=True)
    result, code = run_or_exit_code("hrp2-console study estop", store, lambda: run_study(config, backend, store))
    if code is not None:
        return code
    summaries = summarise(result.outcomes)
    write_runs_csv(result, store, paths["runs"])
    write_params_csv(summaries, paths["params"])
    text = summary_markdown(result, summaries)
    paths["summary"].write_text(text)
    if not args.no_plots:
        plot_heatmaps(summaries, paths["heatmap"], f"e-stop study: {len(params)} parameter sets x {len(cases)} cases "
                      "(blue: recommended)", result.recommendation.summary)
    print(text, end="")
    print("files: " + ", ".join(str(v) for k, v in paths.items() if k != "heatmap" or not args.no_plots))
    return 0
