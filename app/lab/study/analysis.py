"""What a study's runs say per parameter set (falls rescued, harm, false alarms, CP margin at the flag, peak CP
error, recovery time), which set it recommends, how stable that choice is, and the held-out validation."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.lab.study.space import DEFAULT_T1_S, DEFAULT_T2_S, Case, EstopParams
from app.lab.study.spec import RunSpec
from app.lab.study.wilson import wilson_interval

#: Bootstrap resamples of the tuning cases behind the recommendation's stability.
BOOTSTRAP_RESAMPLES = 1000


def _outcome(result: Mapping[str, Any] | None, what: str) -> float:
    """One number of a run's result: `fell` / `stood` (1.0 or 0.0), margin [mm], peak [mm], recovery [s]; nan when
    the run failed, is missing, or has no such number (no flag: no margin)."""
    if result is None or result["verdict"] == "error":
        return math.nan
    value = {"fell": float(result["verdict"] == "fell"), "stood": float(result["verdict"] == "stood"),
             "margin_mm": result["edge_margin_at_flag_m"], "peak_mm": result["peak_cp_error_m"],
             "recovery_s": result["below_threshold_after_revert_s"],
             "flag": float(result["flag_time_s"] is not None)}[what]
    if value is None:
        return math.nan
    return float(value) * (1e3 if what in ("margin_mm", "peak_mm") else 1.0)


def disturbed_nominal(result: Mapping[str, Any] | None) -> bool:
    """A nominal (undisturbed) task the flag got in the way of: the flag rose, or the run failed or fell (a flag
    that stops the valve's approach walk leaves the rim out of the planner's reach: the run ends in an error)."""
    if result is None:
        return False
    return result["verdict"] != "stood" or result["flag_time_s"] is not None


@dataclass(frozen=True)
class Outcomes:
    """The study's runs as arrays (P parameter sets x C cases; nan: failed or not applicable)."""

    params: list[EstopParams]
    cases: list[Case]
    stood_with: np.ndarray  # (P, C) 1.0 stood with the EmergencyStopper
    fell_without: np.ndarray  # (P, C) 1.0 fell without it (the run at P's threshold)
    flagged: np.ndarray  # (P, C) 1.0 the flag rose (with it)
    margin_mm: np.ndarray  # (P, C) CP distance inside the support polygon when the flag rose [mm]
    peak_mm: np.ndarray  # (P, C) peak CP error [mm]
    recovery_s: np.ndarray  # (P, C) from the end of the revert until the error stays under the threshold [s]
    false_alarms: np.ndarray  # (P,) nominal tasks the flag got in the way of at P's threshold
    nominal: int  # how many nominal tasks


def collect(params: Sequence[EstopParams], cases: Sequence[Case], nominal: Sequence[Case],
            result_of: Callable[[RunSpec], Mapping[str, Any] | None], duration_s: float | None) -> Outcomes:
    """The arrays from the stored results (`result_of(spec)`: the result or None)."""
    P, C = len(params), len(cases)
    arrays = {k: np.full((P, C), math.nan) for k in ("stood", "fell", "flag", "margin_mm", "peak_mm", "recovery_s")}
    false_alarms = np.zeros(P)
    for i, p in enumerate(params):
        for j, c in enumerate(cases):
            with_es = result_of(RunSpec(c, True, p, duration_s))
            for k in ("stood", "flag", "margin_mm", "peak_mm", "recovery_s"):
                arrays[k][i, j] = _outcome(with_es, k)
            arrays["fell"][i, j] = _outcome(result_of(RunSpec.baseline(c, p.threshold_m, duration_s)), "fell")
        nominal_params = EstopParams(p.threshold_m, DEFAULT_T1_S, DEFAULT_T2_S)
        false_alarms[i] = sum(disturbed_nominal(result_of(RunSpec(c, True, nominal_params, duration_s)))
                              for c in nominal)
    return Outcomes(list(params), list(cases), arrays["stood"], arrays["fell"], arrays["flag"], arrays["margin_mm"],
                    arrays["peak_mm"], arrays["recovery_s"], false_alarms, len(nominal))


def _median(values: np.ndarray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else None


@dataclass(frozen=True)
class ParamSummary:
    """One parameter set over the tuning cases (those whose runs with and without the EmergencyStopper both
    finished). `rescued`: fell without it and stood with it; `harmed`: stood without it and fell with it."""

    params: EstopParams
    cases: int
    fell_without: int
    rescued: int
    harmed: int
    stood_with: int
    false_alarms: int
    nominal: int
    margin_at_flag_mm: float | None  # median over the flagged runs
    peak_error_mm: float | None  # median over all runs with it
    recovery_s: float | None  # median over the flagged runs back under the threshold
    unrecovered: int  # flagged runs (with it) never back under the threshold

    @property
    def rescue_share(self) -> float | None:
        return self.rescued / self.fell_without if self.fell_without else None

    @property
    def stood_share(self) -> float | None:
        return self.stood_with / self.cases if self.cases else None

    def rank_key(self) -> tuple:
        """Larger is better: no false alarm; most cases standing; most falls rescued; least harm; most CP margin
        at the flag; least peak error; fewest runs not back under the threshold; quickest recovery."""
        def big(v):  # a missing figure ranks last
            return -math.inf if v is None else v

        def small(v):
            return -math.inf if v is None else -v

        return (self.false_alarms == 0, big(self.stood_share), big(self.rescue_share), -self.harmed,
                big(self.margin_at_flag_mm), small(self.peak_error_mm), -self.unrecovered, small(self.recovery_s))


def summarise(o: Outcomes, columns: np.ndarray | None = None) -> list[ParamSummary]:
    """Per parameter set over the case columns `columns` (default: all; repeats count, for the bootstrap)."""
    cols = np.arange(len(o.cases)) if columns is None else columns
    out = []
    for i, p in enumerate(o.params):
        stood, fell = o.stood_with[i, cols], o.fell_without[i, cols]
        valid = np.isfinite(stood) & np.isfinite(fell)
        stood, fell = stood[valid] == 1.0, fell[valid] == 1.0
        flagged = (o.flagged[i, cols] == 1.0)[valid]
        recovery = o.recovery_s[i, cols][valid]
        out.append(ParamSummary(
            p, int(valid.sum()), int(fell.sum()), int((fell & stood).sum()), int((~fell & ~stood).sum()),
            int(stood.sum()), int(o.false_alarms[i]), o.nominal, _median(o.margin_mm[i, cols][valid][flagged]),
            _median(o.peak_mm[i, cols][valid]), _median(recovery[flagged & stood]),
            int((flagged & stood & ~np.isfinite(recovery)).sum())))
    return out


def best(summaries: Sequence[ParamSummary]) -> ParamSummary:
    """The highest rank_key; among equals the first in (threshold, T1, T2) order."""
    return max(sorted(summaries, key=lambda s: s.params, reverse=True), key=lambda s: s.rank_key())


@dataclass(frozen=True)
class Recommendation:
    summary: ParamSummary
    chosen_share: float  # share of bootstrap resamples of the tuning cases that choose the same set
    threshold_share: float  # ... that choose the same threshold
    resamples: int
    rescue_interval: tuple[float, float] | None  # Wilson 95 % of rescued / fell without, tuning cases


def recommend(o: Outcomes, resamples: int = BOOTSTRAP_RESAMPLES, seed: int = 0) -> Recommendation:
    """The best set over all tuning cases, and how often resampling the cases (with replacement, seeded)
    picks it again."""
    chosen = best(summarise(o))
    rng = np.random.default_rng(seed)
    same = same_threshold = 0
    for _ in range(resamples):
        pick = best(summarise(o, rng.integers(0, len(o.cases), len(o.cases)))).params
        same += pick == chosen.params
        same_threshold += pick.threshold_m == chosen.params.threshold_m
    interval = wilson_interval(chosen.rescued, chosen.fell_without)
    return Recommendation(chosen, same / resamples if resamples else math.nan,
                          same_threshold / resamples if resamples else math.nan, resamples, interval)


@dataclass(frozen=True)
class Validation:
    """The recommended set on held-out cases: each run without the EmergencyStopper and with it."""

    params: EstopParams
    cases: int  # held-out cases whose two runs both finished
    errors: int  # held-out cases with a failed run (the planner could not reach)
    fell_without: int
    rescued: int  # fell without, stood with
    harmed: int  # stood without, fell with
    flagged_standing: int  # stood without it, the flag rose with it (the motion was stopped)

    @property
    def rescue_share(self) -> float | None:
        return self.rescued / self.fell_without if self.fell_without else None

    @property
    def rescue_interval(self) -> tuple[float, float] | None:
        return wilson_interval(self.rescued, self.fell_without)


def validate(params: EstopParams, cases: Sequence[Case], result_of, duration_s: float | None) -> Validation:
    o = collect([params], cases, [], result_of, duration_s)
    stood, fell, flag = o.stood_with[0], o.fell_without[0], o.flagged[0]
    valid = np.isfinite(stood) & np.isfinite(fell)
    s, f = stood[valid] == 1.0, fell[valid] == 1.0
    return Validation(params, int(valid.sum()), int((~valid).sum()), int(f.sum()), int((f & s).sum()),
                      int((~f & ~s).sum()), int((~f & (flag[valid] == 1.0)).sum()))
