"""One study run in a worker process (a pool's or a Ray worker's): its deterministic result and its timing."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

from app.lab.study.spec import SETTLE_S, RunSpec

#: The result fields a run reports; the same run gives the same values wherever it runs.
RESULT_FIELDS = ("verdict", "flag_time_s", "peak_cp_error_m", "cp_error_at_flag_m", "edge_margin_at_flag_m",
                 "min_edge_margin_m", "below_threshold_after_revert_s", "duration_s", "outcome", "refused",
                 "faults", "error")


def quiet_controller_log() -> None:
    """A worker has no logging set up, so Python would print the controller's errors ("fall detected ...": a
    result here, not news) to stderr over the progress bar; a handler that drops them stops that. Where the
    caller has set logging up, the records still reach its handlers."""
    logger = logging.getLogger("controller")
    if not logger.handlers:
        logger.addHandler(logging.NullHandler())


def run_spec(spec: dict[str, Any]) -> dict[str, Any]:
    """Run `spec` (RunSpec.to_dict()) in a fresh simulation: {"key", "result", "timing"}. An exception of the
    experiment (the planner's IK cannot reach a disturbed valve) is the result `verdict: "error"`, not a crash."""
    from app.lab.experiments import run_experiment

    quiet_controller_log()
    s = RunSpec.from_dict(spec)
    t0 = time.perf_counter()
    try:
        r = run_experiment(s.case.experiment, es=s.es, plot=False, write_csv=False, variant=s.case.variant,
                           params=s.params.layer_params(), duration_s=s.duration_s, disturbance=s.case.values(),
                           settle_s=SETTLE_S)
    except Exception as exc:  # noqa: BLE001 - the study records it and goes on
        result = {f: None for f in RESULT_FIELDS} | {"verdict": "error", "error": f"{type(exc).__name__}: {exc}"}
        return {"key": s.key(), "result": result, "timing": {"wall_s": time.perf_counter() - t0, "sim_s": 0.0}}
    result = {"verdict": r.verdict, "flag_time_s": r.flag_time_s, "peak_cp_error_m": r.peak_cp_error_m,
              "cp_error_at_flag_m": r.cp_error_at_flag_m, "edge_margin_at_flag_m": r.edge_margin_at_flag_m,
              "min_edge_margin_m": r.min_edge_margin_m,
              "below_threshold_after_revert_s": r.below_threshold_after_revert_s, "duration_s": r.duration_s,
              "outcome": dict(r.outcome), "refused": list(r.refused), "faults": list(r.faults), "error": None}
    return {"key": s.key(), "result": result,
            "timing": {"wall_s": time.perf_counter() - t0, "sim_s": SETTLE_S + r.duration_s}}


def run_timed(spec, run: Callable[[Any], tuple[dict[str, Any], float]], fields: tuple[str, ...]) -> dict[str, Any]:
    """A walking study's run in a fresh simulation: `run(spec)` gives its result and the seconds simulated; returns
    {"key", "result", "timing"}. A failure of the run itself is the result `outcome: "error"` (every other field of
    `fields` None), not a crash."""
    quiet_controller_log()
    t0 = time.perf_counter()
    try:
        result, sim_s = run(spec)
    except Exception as exc:  # noqa: BLE001 - the study records it and goes on
        result = {f: None for f in fields} | {"outcome": "error", "error": f"{type(exc).__name__}: {exc}"}
        sim_s = 0.0
    return {"key": spec.key(), "result": result, "timing": {"wall_s": time.perf_counter() - t0, "sim_s": sim_s}}
