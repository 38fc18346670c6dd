"""The phases of an e-stop study: the tuning runs (every parameter set on every case with the EmergencyStopper,
every case without it at every threshold, the nominal tasks at every threshold), the analysis and the
recommendation, then the held-out validation of the recommended set. Finished runs are taken from the store."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from app.lab.study.analysis import Outcomes, Recommendation, Validation, collect, recommend, validate
from app.lab.study.progress import Progress
from app.lab.study.space import DEFAULT_T1_S, DEFAULT_T2_S, Case, EstopParams
from app.lab.study.spec import RunSpec
from app.lab.study.store import RunStore


@dataclass(frozen=True)
class StudyConfig:
    params: list[EstopParams]
    cases: list[Case]  # tuning
    validation_cases: list[Case]  # held out: none of them is a tuning case
    nominal: list[Case] = field(default_factory=list)  # undisturbed tasks: the flag must not rise
    duration_s: float | None = None  # [s] every experiment ends early (tests)
    bootstrap_resamples: int = 1000
    seed: int = 0  # the bootstrap's

    def __post_init__(self) -> None:
        if not self.params or not self.cases:
            raise ValueError("a study needs at least one parameter set and one case")
        shared = set(self.cases) & set(self.validation_cases)
        if shared:
            raise ValueError(f"{len(shared)} held-out case(s) are also tuning cases, e.g. {next(iter(shared)).label()}")


@dataclass(frozen=True)
class PhaseStats:
    """What one phase ran in this invocation: runs done now and found done, simulated and wall seconds."""

    label: str
    runs: int
    skipped: int
    sim_s: float
    wall_s: float

    @property
    def sim_per_wall(self) -> float | None:
        return self.sim_s / self.wall_s if self.runs and self.wall_s > 0 else None


@dataclass(frozen=True)
class StudyResult:
    config: StudyConfig
    outcomes: Outcomes
    recommendation: Recommendation
    validation: Validation | None
    phases: tuple[PhaseStats, ...]
    errors: tuple[str, ...]  # distinct failures of runs (the planner could not reach, ...)


def unique(specs: Sequence[RunSpec]) -> list[RunSpec]:
    return list({s.key(): s for s in specs}.values())


def tuning_specs(config: StudyConfig) -> list[RunSpec]:
    d = config.duration_s
    thresholds = sorted({p.threshold_m for p in config.params})
    specs = [RunSpec(c, True, p, d) for p in config.params for c in config.cases]
    specs += [RunSpec.baseline(c, th, d) for th in thresholds for c in config.cases]
    specs += [RunSpec(c, True, EstopParams(th, DEFAULT_T1_S, DEFAULT_T2_S), d) for th in thresholds
              for c in config.nominal]
    return unique(specs)


def validation_specs(config: StudyConfig, params: EstopParams) -> list[RunSpec]:
    d = config.duration_s
    return unique([s for c in config.validation_cases
                   for s in (RunSpec.baseline(c, params.threshold_m, d), RunSpec(c, True, params, d))])


def execute(label: str, specs: Sequence[RunSpec], backend, store: RunStore, stream: TextIO | None = None
            ) -> PhaseStats:
    """Run the specs the store does not hold yet on `backend`, storing each as it finishes."""
    todo = [s for s in unique(specs) if s.key() not in store]
    by_key = {s.key(): s for s in todo}
    progress = Progress(label, len(todo), sum(s.expected_sim_s() for s in todo), stream=stream)
    if todo:
        progress.start()
    t0 = time.perf_counter()
    sim_s = 0.0
    ran = 0
    for record in backend.run([s.to_dict() for s in todo]):
        spec = by_key[record["key"]]
        store.add({"key": record["key"], "spec": spec.to_dict(), "result": record["result"],
                   "timing": record["timing"]})
        sim_s += record["timing"]["sim_s"]
        ran += 1
        progress.done(spec.expected_sim_s())
    return PhaseStats(label, ran, len(specs) - len(todo), sim_s, time.perf_counter() - t0 if ran else 0.0)


def result_getter(store: RunStore):
    def result_of(spec: RunSpec) -> dict[str, Any] | None:
        key = spec.key()
        return store.get(key)["result"] if key in store else None

    return result_of


def run_study(config: StudyConfig, backend, store: RunStore, stream: TextIO | None = None) -> StudyResult:
    tuning = tuning_specs(config)
    phases = [execute("tuning", tuning, backend, store, stream)]
    result_of = result_getter(store)
    outcomes = collect(config.params, config.cases, config.nominal, result_of, config.duration_s)
    rec = recommend(outcomes, config.bootstrap_resamples, config.seed)
    validation = None
    specs = list(tuning)
    if config.validation_cases:
        held_out = validation_specs(config, rec.summary.params)
        phases.append(execute("validation", held_out, backend, store, stream))
        validation = validate(rec.summary.params, config.validation_cases, result_of, config.duration_s)
        specs += held_out
    errors = sorted({store.get(s.key())["result"]["error"] for s in specs
                     if s.key() in store and store.get(s.key())["result"]["verdict"] == "error"})
    return StudyResult(config, outcomes, rec, validation, tuple(phases), tuple(errors))


def study_paths(out_dir: Path) -> dict[str, Path]:
    return {"store": out_dir / "runs.jsonl", "runs": out_dir / "runs.csv", "params": out_dir / "params.csv",
            "summary": out_dir / "summary.md", "heatmap": out_dir / "heatmap.png"}
