"""One run of an e-stop study: a case, with or without the EmergencyStopper, a parameter set and the run's
length; its key (a hash of exactly these) names it in the store, so a restart finds it finished."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import Any

from app.lab.experiments import EXPERIMENTS
from app.lab.study.space import DEFAULT_T1_S, DEFAULT_T2_S, Case, EstopParams

#: Bump when a change makes stored results stale (what a run does or what it reports).
STORE_FORMAT = 1
SETTLE_S = 2.5  # [s] each run stands this long before the experiment (run_experiment's default)


@dataclass(frozen=True)
class RunSpec:
    """Without the EmergencyStopper T1 and T2 do nothing: such a run carries the defaults, so that one baseline
    serves every (T1, T2) of its threshold."""

    case: Case
    es: bool
    params: EstopParams
    duration_s: float | None = None  # [s] the experiment ends early; None: its own duration

    @classmethod
    def baseline(cls, case: Case, threshold_m: float, duration_s: float | None = None) -> RunSpec:
        return cls(case, False, EstopParams(threshold_m, DEFAULT_T1_S, DEFAULT_T2_S), duration_s)

    def to_dict(self) -> dict[str, Any]:
        return {"format": STORE_FORMAT, "experiment": self.case.experiment, "variant": self.case.variant,
                "disturbance": [[k, v] for k, v in self.case.disturbance], "es": self.es,
                "threshold_m": self.params.threshold_m, "t1_s": self.params.t1_s, "t2_s": self.params.t2_s,
                "duration_s": self.duration_s}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RunSpec:
        case = Case(d["experiment"], d["variant"], tuple((k, float(v)) for k, v in d["disturbance"]))
        return cls(case, bool(d["es"]), EstopParams(d["threshold_m"], d["t1_s"], d["t2_s"]), d["duration_s"])

    def key(self) -> str:
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def expected_sim_s(self) -> float:
        """[s] simulated if nothing ends it early (a fall does): for the progress bar's estimate."""
        duration = EXPERIMENTS[self.case.experiment].duration_s
        return SETTLE_S + (duration if self.duration_s is None else min(duration, self.duration_s))
