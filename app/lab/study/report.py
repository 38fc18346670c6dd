"""A study's tables: every run (CSV), every parameter set (CSV and Markdown), and the summary (Markdown): the
recommended parameters with their confidence, the held-out validation, the throughput."""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path

from app.lab.study.analysis import ParamSummary
from app.lab.study.store import RunStore
from app.lab.study.study import StudyResult, tuning_specs, validation_specs

RUN_COLUMNS = ("key", "experiment", "variant", "disturbance", "es", "threshold_mm", "t1_s", "t2_s", "verdict",
               "flag_time_s", "cp_margin_at_flag_mm", "peak_cp_error_mm", "min_cp_margin_mm",
               "back_under_threshold_s", "outcome", "error", "sim_s", "wall_s")
PARAM_COLUMNS = ("threshold_mm", "t1_s", "t2_s", "cases", "fell_without_es", "rescued", "harmed", "stood_with_es",
                 "false_alarms", "cp_margin_at_flag_mm", "peak_cp_error_mm", "recovery_s", "unrecovered")


def _num(v, scale: float = 1.0, fmt: str = "{:.4g}") -> str:
    return "" if v is None else fmt.format(v * scale)


def write_runs_csv(result: StudyResult, store: RunStore, path: Path) -> None:
    specs = tuning_specs(result.config)
    if result.validation is not None:
        specs += validation_specs(result.config, result.validation.params)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(RUN_COLUMNS)
        for s in specs:
            if s.key() not in store:
                continue
            rec = store.get(s.key())
            r, t = rec["result"], rec["timing"]
            w.writerow([s.key(), s.case.experiment, s.case.variant,
                        " ".join(f"{k}={v:g}" for k, v in s.case.disturbance), int(s.es),
                        f"{s.params.threshold_m * 1e3:g}", f"{s.params.t1_s:g}", f"{s.params.t2_s:g}", r["verdict"],
                        _num(r["flag_time_s"]), _num(r["edge_margin_at_flag_m"], 1e3), _num(r["peak_cp_error_m"], 1e3),
                        _num(r["min_edge_margin_m"], 1e3), _num(r["below_threshold_after_revert_s"]),
                        " ".join(f"{k}={v:.4g}" for k, v in (r["outcome"] or {}).items()), r["error"] or "",
                        f"{t['sim_s']:.3f}", f"{t['wall_s']:.3f}"])


def param_row(s: ParamSummary) -> list[str]:
    return [f"{s.params.threshold_m * 1e3:g}", f"{s.params.t1_s:g}", f"{s.params.t2_s:g}", str(s.cases),
            str(s.fell_without), str(s.rescued), str(s.harmed), str(s.stood_with), f"{s.false_alarms}/{s.nominal}",
            _num(s.margin_at_flag_mm, fmt="{:.0f}"), _num(s.peak_error_mm, fmt="{:.0f}"),
            _num(s.recovery_s, fmt="{:.2f}"), str(s.unrecovered)]


def write_params_csv(summaries: Sequence[ParamSummary], path: Path) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(PARAM_COLUMNS)
        w.writerows(param_row(s) for s in summaries)


def _share(k: int, n: int, interval) -> str:
    if n == 0:
        return "n/a (none)"
    lo, hi = interval
    return f"{k}/{n} = {100 * k / n:.0f} % (95 % Wilson {100 * lo:.0f}-{100 * hi:.0f} %)"


def summary_markdown(result: StudyResult, summaries: Sequence[ParamSummary], top: int = 10) -> str:
    rec = result.recommendation
    s = rec.summary
    cfg = result.config
    lines = [f"**Recommended: {s.params.label()}** (tuning: {len(cfg.params)} parameter sets x {len(cfg.cases)} "
             f"cases, with and without the EmergencyStopper, and {s.nominal} nominal tasks per threshold)", ""]
    lines.append(f"- tuning cases: {s.cases} finished; without the EmergencyStopper {s.fell_without} fell; with it "
                 f"{s.stood_with} stood; falls rescued {_share(s.rescued, s.fell_without, rec.rescue_interval)}; "
                 f"harmed (stood without, fell with) {s.harmed}; false alarms on the nominal tasks "
                 f"{s.false_alarms}/{s.nominal}")
    lines.append(f"- median CP margin at the flag {_num(s.margin_at_flag_mm, fmt='{:.0f}')} mm, median peak CP error "
                 f"{_num(s.peak_error_mm, fmt='{:.0f}')} mm, median recovery {_num(s.recovery_s, fmt='{:.2f}')} s "
                 f"({s.unrecovered} flagged runs never back under the threshold)")
    lines.append(f"- confidence in the choice: {rec.resamples} bootstrap resamples of the tuning cases choose this set "
                 f"{100 * rec.chosen_share:.0f} % of the time, this threshold {100 * rec.threshold_share:.0f} %")
    v = result.validation
    if v is not None:
        lines.append(f"- held-out validation ({v.cases} cases not tuned on, {v.errors} not run to the end): fell "
                     f"without the EmergencyStopper {v.fell_without}; of those stood with it "
                     f"{_share(v.rescued, v.fell_without, v.rescue_interval)} (goal >= 95 %); harmed {v.harmed}; "
                     f"flag raised in {v.flagged_standing} that stood without it")
    for p in result.phases:
        rate = "" if p.sim_per_wall is None else f", {p.sim_per_wall:.2f} simulated s per wall s"
        lines.append(f"- {p.label}: {p.runs} runs now ({p.skipped} already stored), {p.sim_s:.0f} s simulated in "
                     f"{p.wall_s:.0f} s{rate}")
    if result.errors:
        lines.append(f"- runs that failed ({len(result.errors)} distinct): " + "; ".join(result.errors[:3]))
    lines += ["", "| threshold [mm] | T1 [s] | T2 [s] | cases | fell w/o ES | rescued | harmed | stood with ES "
              "| false alarms | CP margin at flag [mm] | peak CP error [mm] | recovery [s] | unrecovered |",
              "|" + "---|" * len(PARAM_COLUMNS)]
    ranked = sorted(summaries, key=lambda x: x.rank_key(), reverse=True)
    for x in ranked[:top]:
        lines.append("| " + " | ".join(param_row(x)) + " |")
    if len(ranked) > top:
        lines.append(f"\n({top} best of {len(ranked)} by the ranking; all in params.csv)")
    return "\n".join(lines) + "\n"
