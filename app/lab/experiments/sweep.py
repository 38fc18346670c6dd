"""How the flag threshold, T1 and T2 were chosen: `python -m app.lab.experiments.sweep [NAME]` runs an
experiment over a grid of them and prints a Markdown table (verdict, flag time, CP margin at the flag,
peak CP error, time back under the threshold after the revert)."""

from __future__ import annotations

import sys
from itertools import product

from app.lab.experiments import run_experiment

THRESHOLDS_M = (0.02, 0.04, 0.06, 0.08)
T1_S = (0.25, 0.5, 1.0, 1.5)
T2_S = (0.25, 0.5, 1.0)


def _mm(v: float | None) -> str:
    return "-" if v is None else f"{v * 1e3:.0f}"


def sweep(name: str, variant: str | None = None) -> list[str]:
    rows = ["| threshold [mm] | T1 [s] | T2 [s] | verdict | flag [s] | CP margin at flag [mm] | peak error [mm] "
            "| back under threshold [s] |", "|---|---|---|---|---|---|---|---|"]
    grid = [(th, 1.0, 0.5) for th in THRESHOLDS_M] + [(0.04, t1, t2) for t1, t2 in product(T1_S, T2_S)]
    for threshold, t1, t2 in dict.fromkeys(grid):
        r = run_experiment(name, variant=variant, plot=False,
                           params={"st": {"cp_threshold_m": threshold}, "es": {"t1_s": t1, "t2_s": t2}})
        flag = "-" if r.flag_time_s is None else f"{r.flag_time_s:.2f}"
        back = "-" if r.below_threshold_after_revert_s is None else f"{r.below_threshold_after_revert_s:.2f}"
        rows.append(f"| {threshold * 1e3:.0f} | {t1} | {t2} | {r.verdict} | {flag} | {_mm(r.edge_margin_at_flag_m)} "
                    f"| {_mm(r.peak_cp_error_m)} | {back} |")
        print(rows[-1], flush=True)
    return rows


if __name__ == "__main__":
    sweep(sys.argv[1] if len(sys.argv) > 1 else "wall-push-forward", sys.argv[2] if len(sys.argv) > 2 else None)
