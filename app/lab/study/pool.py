"""Study runs on a local pool of spawned processes (each run builds its own simulation, so the results do not
depend on how many run at once)."""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

from app.lab.study.run import run_spec

MAX_WORKERS = 64


class PoolBackend:
    """`run(specs)` yields each run's record as it finishes, from `workers` spawned processes; `fn` runs one spec
    (a module-level function: the e-stop study's `run_spec` by default, the push map's `run_push`)."""

    def __init__(self, workers: int, fn: Callable[[dict[str, Any]], dict[str, Any]] = run_spec) -> None:
        if not 1 <= workers <= MAX_WORKERS:
            raise ValueError(f"workers must be 1..{MAX_WORKERS}, got {workers}")
        self.workers = workers
        self.fn = fn

    def __repr__(self) -> str:
        return f"PoolBackend(workers={self.workers})"

    def describe(self) -> str:
        return f"a local pool of {self.workers} process{'es' if self.workers > 1 else ''}"

    def run(self, specs: Sequence[dict[str, Any]]) -> Iterator[dict[str, Any]]:
        if not specs:
            return
        ctx = multiprocessing.get_context("spawn")
        pool = ProcessPoolExecutor(max_workers=min(self.workers, len(specs)), mp_context=ctx)
        try:
            futures = [pool.submit(self.fn, s) for s in specs]
            for future in as_completed(futures):
                yield future.result()
        finally:  # also when the caller stops early (Ctrl-C): queued runs are dropped, running ones finish
            pool.shutdown(wait=True, cancel_futures=True)
