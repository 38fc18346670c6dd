"""What an e-stop study varies: the (threshold, T1, T2) sets, as a grid or a seeded sample, and the disturbance
cases, as a seeded sample or a one-factor-at-a-time grid over the experiments' declared disturbances."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import product

import numpy as np

from app.lab.experiments import EXPERIMENTS

#: The study's limits of each parameter: the CLI refuses values outside them.
THRESHOLD_LIMITS_M = (0.005, 0.2)  # [m] below 5 mm the standing robot's own noise flags
T1_LIMITS_S = (0.0, 3.0)  # [s] 0: stop where the plan is (no revert)
T2_LIMITS_S = (0.05, 3.0)  # [s] at least ten ticks for the revert
#: The EmergencyStopper's defaults (controller/layers/emergency_stopper.py): runs without it carry these.
DEFAULT_T1_S, DEFAULT_T2_S = 1.0, 0.5

#: The variant each experiment is studied in: the one whose declared disturbances are the whole disturbance
#: (the valve's `undisturbed` plus its offsets; the door has no continuous disturbance: its pushing plan).
STUDY_VARIANTS = {"wall-push-forward": "default", "wall-push-left": "default", "valve": "undisturbed",
                  "door": "push-plan"}
#: Decimals the sampled disturbances are rounded to, by unit (1 mm, 0.1 deg, 0.1 mm/s).
ROUNDING = {"m": 3, "deg": 1, "m/s": 4}


@dataclass(frozen=True, order=True)
class EstopParams:
    """One parameter set: the Stabilizer's flag threshold [m] on |CP error|, the EmergencyStopper's T1 (how far
    back the revert goes) and T2 (how long it takes) [s]."""

    threshold_m: float
    t1_s: float
    t2_s: float

    def layer_params(self) -> dict[str, dict[str, float]]:
        """The layer parameter document that sets them."""
        return {"st": {"cp_threshold_m": self.threshold_m}, "es": {"t1_s": self.t1_s, "t2_s": self.t2_s}}

    def label(self) -> str:
        return f"threshold {self.threshold_m * 1e3:g} mm, T1 {self.t1_s:g} s, T2 {self.t2_s:g} s"


@dataclass(frozen=True)
class Case:
    """One disturbance case: an experiment, its variant and every one of its declared disturbances (in the
    declaration order), so that equal cases are equal however they were written."""

    experiment: str
    variant: str
    disturbance: tuple[tuple[str, float], ...]

    @classmethod
    def make(cls, experiment: str, variant: str | None = None, values: Mapping[str, float] | None = None) -> Case:
        if experiment not in EXPERIMENTS:
            raise ValueError(f"unknown experiment {experiment!r}; available: {', '.join(EXPERIMENTS)}")
        exp = EXPERIMENTS[experiment]
        variant = STUDY_VARIANTS.get(experiment, exp.variants[0]) if variant is None else variant
        if variant not in exp.variants:
            raise ValueError(f"unknown variant {variant!r} of {experiment}; available: {', '.join(exp.variants)}")
        return cls(experiment, variant, tuple(exp.disturbance(values).items()))

    def values(self) -> dict[str, float]:
        return dict(self.disturbance)

    def label(self) -> str:
        exp = EXPERIMENTS[self.experiment]
        changed = [f"{k} {v:g}" for k, v in self.disturbance if v != exp.disturbances[k].default]
        return f"{self.experiment} [{self.variant}]" + (f" {', '.join(changed)}" if changed else "")


#: Undisturbed tasks: the flag must not rise in them (there a flag is a false alarm that stops the task).
NOMINAL = (("valve", "undisturbed"), ("door", "pull"))


def nominal_cases(experiments: Sequence[str]) -> list[Case]:
    """The nominal tasks of the studied experiments."""
    return [Case.make(e, v) for e, v in NOMINAL if e in experiments]


def param_grid(thresholds_m: Sequence[float], t1_s: Sequence[float], t2_s: Sequence[float]) -> list[EstopParams]:
    """Every combination, in the order given (threshold slowest)."""
    combos = product(thresholds_m, t1_s, t2_s)
    return list(dict.fromkeys(EstopParams(float(a), float(b), float(c)) for a, b, c in combos))


def param_sample(n: int, seed: int, threshold_range_m: tuple[float, float], t1_range_s: tuple[float, float],
                 t2_range_s: tuple[float, float]) -> list[EstopParams]:
    """`n` distinct sets drawn uniformly in the ranges (seeded), rounded to 1 mm and 0.05 s."""
    rng = np.random.default_rng(seed)
    out: dict[EstopParams, None] = {}
    for _ in range(1000 * n):
        if len(out) == n:
            break
        out[EstopParams(_rounded(rng.uniform(*threshold_range_m), 0.001), _rounded(rng.uniform(*t1_range_s), 0.05),
                        _rounded(rng.uniform(*t2_range_s), 0.05))] = None
    if len(out) < n:
        raise ValueError(f"the ranges hold fewer than {n} distinct parameter sets at 1 mm / 0.05 s")
    return list(out)


def _rounded(x: float, step: float) -> float:
    return round(round(float(x) / step) * step, 6)


def allocation(n: int, experiments: Sequence[str]) -> dict[str, int]:
    """How many of `n` sampled cases go to each experiment that declares disturbances: in proportion to how
    many it declares (each disturbance dimension equally represented), largest remainders first."""
    varied = [e for e in experiments if EXPERIMENTS[e].disturbances]
    if not varied:
        return {}
    weights = np.array([len(EXPERIMENTS[e].disturbances) for e in varied], dtype=float)
    exact = n * weights / weights.sum()
    counts = np.floor(exact).astype(int)
    for i in np.argsort(-(exact - counts), kind="stable")[: n - int(counts.sum())]:
        counts[i] += 1
    return {e: int(c) for e, c in zip(varied, counts, strict=True)}


def fixed_cases(experiments: Sequence[str]) -> list[Case]:
    """One case for each experiment without declared disturbances (the door's pushing plan)."""
    return [Case.make(e) for e in experiments if not EXPERIMENTS[e].disturbances]


def case_sample(n: int, seed: int, experiments: Sequence[str]) -> list[Case]:
    """`n` cases with every declared disturbance drawn uniformly in its range (seeded; rounded by unit), spread
    over the experiments by `allocation`."""
    rng = np.random.default_rng(seed)
    cases = []
    for experiment, count in allocation(n, experiments).items():
        declared = EXPERIMENTS[experiment].disturbances
        for _ in range(count):
            values = {k: round(float(rng.uniform(d.low, d.high)), ROUNDING.get(d.unit, 4)) for k, d in declared.items()}
            cases.append(Case.make(experiment, None, values))
    return cases


def case_grid(levels: int, experiments: Sequence[str]) -> list[Case]:
    """One factor at a time: each declared disturbance at `levels` evenly spaced values of its range, the others
    at their defaults (the default case once)."""
    cases: dict[Case, None] = {}
    for experiment in experiments:
        declared = EXPERIMENTS[experiment].disturbances
        cases[Case.make(experiment)] = None
        for name, d in declared.items():
            for v in np.linspace(d.low, d.high, levels):
                cases[Case.make(experiment, None, {name: round(float(v), ROUNDING.get(d.unit, 4))})] = None
    return list(cases)
