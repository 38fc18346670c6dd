"""Recorded traces of the robot's behaviour (stand, walk, push, the four [MLC] experiments): digests of
their per-tick data, so a refactor that must not change behaviour can prove it did not.

`python -m tests.scenarios.traces --write` records them into tests/data/traces.json (do it only when a
change is meant to alter behaviour, and say so in the commit)."""

from __future__ import annotations

import argparse
import hashlib
import json
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

TRACES_FILE = Path(__file__).resolve().parents[1] / "data" / "traces.json"
SUBSAMPLE = 20  # ticks between the rows kept for diagnosis


def _digest(a: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(a, dtype=np.float64).tobytes()).hexdigest()


def _loop_trace(script: Callable, seconds: float) -> dict:
    """Run `script(loop)` after building a fresh simulated robot, then `seconds` of ticks; the trace is the
    commanded joints [rad] and the simulated BODY position [m] of every tick."""
    from tests.scenarios.helpers import make_system

    system = make_system()
    loop = system.loop
    script(loop)
    rows = []
    for _ in range(int(round(seconds / loop.dt_control_s))):
        snap = loop.step()
        rows.append(np.concatenate((snap.q_cmd_rad, snap.truth.base_pos_world)))
    a = np.array(rows)
    return {"sha256": _digest(a), "ticks": len(a), "rows": a[::SUBSAMPLE].round(9).tolist()}


def _stand(loop) -> None:
    """Nothing: the chain holds half-sitting."""


def _walk(loop) -> None:
    loop.run_for(2.5)
    loop.call(lambda: loop.chain["abc"].go_velocity(0.1, 0.0, 0.0))


def _push(loop) -> None:
    loop.run_for(2.5)
    loop.call(lambda: loop.plant.push("BODY", np.array([200.0, 0.0, 0.0]), 0.1))


LOOP_TRACES: dict[str, tuple[Callable, float]] = {
    "stand": (_stand, 4.0),
    "walk": (_walk, 6.0),
    "push": (_push, 3.0),
}

EXPERIMENT_TRACES = ("wall-push-forward", "wall-push-left", "valve", "door")


def _experiment_trace(name: str) -> dict:
    """The experiment's own per-tick CSV (CP error, threshold, edge distance, flags) and its outcome."""
    from app.lab.experiments import run_experiment

    with tempfile.TemporaryDirectory() as d:
        r = run_experiment(name, out_dir=Path(d), plot=False)
        text = Path(r.csv_path).read_text()
    values = np.array([[float(v) for v in line.split(",")] for line in text.splitlines()[1:]])
    return {"sha256": hashlib.sha256(text.encode()).hexdigest(), "ticks": len(values),
            "rows": values[::SUBSAMPLE].tolist(), "verdict": r.verdict,
            "flag_time_s": r.flag_time_s, "peak_cp_error_m": round(r.peak_cp_error_m, 9),
            "outcome": {k: round(float(v), 9) for k, v in r.outcome.items()}}


def record(name: str) -> dict:
    if name in LOOP_TRACES:
        script, seconds = LOOP_TRACES[name]
        return _loop_trace(script, seconds)
    return _experiment_trace(name)


ALL_TRACES = (*LOOP_TRACES, *EXPERIMENT_TRACES)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--write", action="store_true", help="record every trace into " + str(TRACES_FILE.name))
    p.add_argument("names", nargs="*", default=list(ALL_TRACES))
    args = p.parse_args()
    out = json.loads(TRACES_FILE.read_text()) if TRACES_FILE.exists() else {}
    for name in args.names:
        out[name] = record(name)
        print(name, out[name]["sha256"][:16])
    if args.write:
        TRACES_FILE.write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
