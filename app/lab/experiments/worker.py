"""One experiment run in a process of its own (spawned per run, so nothing of it stays in the console):
the result, and the CSV and PNG as bytes; its temporary folder is removed before it returns."""

from __future__ import annotations

import dataclasses
import tempfile
import time
from pathlib import Path
from typing import Any


def run_in_worker(name: str, es: bool, variant: str | None, params: dict | None, save: bool,
                  duration_s: float | None = None) -> dict[str, Any]:
    """Runs in the worker process: the ExperimentResult as a dict, plus "csv" / "png" bytes when `save`."""
    from app.lab.experiments import run_experiment

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f"hrp2-{name}-") as d:
        r = run_experiment(name, es=es, out_dir=Path(d) if save else None, plot=save, variant=variant,
                           params=params or None, duration_s=duration_s)
        files = {}
        for key, path in (("csv", r.csv_path), ("png", r.png_path)):
            if path is not None:
                files[key] = Path(path).read_bytes()
    out = dataclasses.asdict(r)
    out["csv_path"] = out["png_path"] = None  # gone with the folder: the bytes travel instead
    out["wall_time_s"] = round(time.perf_counter() - t0, 3)
    out["files"] = files
    return out
