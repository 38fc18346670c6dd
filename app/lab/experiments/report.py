"""Every experiment, variant, with and without the EmergencyStopper: `python -m app.lab.experiments.report
[OUT_DIR]` prints the Markdown table of docs/estop-study.md and writes each run's Fig. 10-like PNG to OUT_DIR
(docs/img/experiments for that page)."""

from __future__ import annotations

import sys
from pathlib import Path

from app.lab.experiments import EXPERIMENTS, run_experiment


def _mm(v: float | None) -> str:
    return "-" if v is None else f"{v * 1e3:.0f}"


def _s(v: float | None) -> str:
    return "-" if v is None else f"{v:.2f}"


def report(out_dir: Path | None) -> list[str]:
    rows = ["| experiment | variant | ES | verdict | flag [s] | CP margin at flag [mm] | peak CP error [mm] "
            "| smallest CP margin [mm] | back under threshold [s] | task | x real time |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, exp in EXPERIMENTS.items():
        for variant in exp.variants:
            for es in (True, False):
                r = run_experiment(name, es=es, out_dir=out_dir, variant=variant, write_csv=False)
                task = ", ".join(f"{k} {v:.1f}" for k, v in r.outcome.items()) or "-"
                rows.append(f"| {name} | {variant} | {'on' if es else 'off'} | {r.verdict} | {_s(r.flag_time_s)} "
                            f"| {_mm(r.edge_margin_at_flag_m)} | {_mm(r.peak_cp_error_m)} | {_mm(r.min_edge_margin_m)} "
                            f"| {_s(r.below_threshold_after_revert_s) if es else '-'} | {task} "
                            f"| {r.real_time_factor:.1f} |")
                print(rows[-1], flush=True)
    return rows


if __name__ == "__main__":
    report(Path(sys.argv[1]) if len(sys.argv) > 1 else None)
