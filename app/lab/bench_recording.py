"""Benchmark of the session recording: what it adds to a tick of the loop (the recorder's work in the loop's
thread, timed directly, and the whole tick with and without it), the writer process's CPU and the file's size,
on the bench's teleop scenario (walking through the walking point, both hands and the head streamed every tick:
an input at every tick, the most the recorder sees)."""

from __future__ import annotations

import math
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from app.lab.bench_scenarios import SCENARIOS
from app.service.local import LocalRobot

WARMUP_S = 2.5  # [s] standing while the AutoBalancer and the Stabilizer blend in (not timed)
RECORDING_SCENARIOS = {"record": "what recording a session adds to a tick: the teleop scenario (an input every tick) "
                                 "without and with recording; the recorder's work timed where it is called, the "
                                 "writer process's CPU, the file's bytes per simulated second"}


def _timed(fn, samples: list[float]):
    """`fn` that appends the CPU time of this thread it took [s] (preemption by other processes excluded: this
    machine's 2 cores are shared; each reading costs a system call, ~0.5 us, counted in)."""
    clock = time.thread_time

    def wrapper(*args, **kwargs):
        t0 = clock()
        try:
            return fn(*args, **kwargs)
        finally:
            samples.append(clock() - t0)

    return wrapper


def _stats_us(samples) -> dict[str, float]:
    a = np.asarray(samples, dtype=float) * 1e6
    if a.size == 0:
        return {"p50_us": 0.0, "p99_us": 0.0, "mean_us": 0.0, "n": 0}
    return {"p50_us": round(float(np.percentile(a, 50)), 2), "p99_us": round(float(np.percentile(a, 99)), 2),
            "mean_us": round(float(a.mean()), 2), "n": int(a.size)}


def _cpu_s(pid: int) -> float:
    """User + system CPU time of a process [s] (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _timer_overhead_s(calls: int = 5000) -> float:
    """What one `_timed` wrapper adds to the time it reports [s] (its own call and clock reading), on average."""
    samples: list[float] = []
    noop = _timed(lambda *args: None, samples)
    for _ in range(calls):
        noop(1, 2)
    return float(np.mean(samples))


def _run(duration_s: float, scene: str, record: Path | None, stream_every: int = 1) -> dict[str, Any]:
    spec = SCENARIOS["teleop"]
    robot = LocalRobot(scene=scene, speed=None, record=record)
    loop = robot.loop
    tick_s: list[float] = []
    tap_s: list[float] = []
    input_s: list[float] = []
    recorder = robot.host.recorder
    if recorder is not None:  # the recorder's own work in the loop's thread, timed where it is called
        recorder.tick = _timed(recorder.tick, tap_s)
        recorder.input = _timed(recorder.input, input_s)
        recorder.setpoints = _timed(recorder.setpoints, input_s)
        recorder.runs_changed = _timed(recorder.runs_changed, tap_s)
    loop.run_for(WARMUP_S)
    tap_s.clear()
    input_s.clear()
    n = max(1, int(round(duration_s / loop.dt_control_s)))
    clock = time.perf_counter
    cpu = time.thread_time
    cpu_s: list[float] = []
    writer_cpu0 = None
    if recorder is not None and recorder.writer_pid is not None:
        writer_cpu0 = _cpu_s(recorder.writer_pid)
    for i in range(n):
        t0, c0 = clock(), cpu()
        if i % stream_every == 0:
            spec.stream(robot)  # the operator's setpoints, applied at the boundary (recorded as inputs)
        loop.step()
        cpu_s.append(cpu() - c0)
        tick_s.append(clock() - t0)
    out: dict[str, Any] = {"tick": _stats_us(tick_s), "tick_cpu": _stats_us(cpu_s),
                           "fallen": bool(robot.host.observation.fallen)}
    if recorder is not None:
        pid = recorder.writer_pid
        writer_cpu = None if writer_cpu0 is None or pid is None else _cpu_s(pid) - writer_cpu0
        status = robot.stop_recording()
        overhead = _timer_overhead_s()
        total = np.asarray(tap_s).sum() + np.asarray(input_s).sum() - overhead * (len(tap_s) + len(input_s))
        out.update({"recorder_tick": _stats_us(tap_s), "recorder_inputs": _stats_us(input_s),
                    "timer_overhead_us": round(overhead * 1e6, 2),
                    "recording_per_tick_us": round(float(total) / n * 1e6, 2),
                    "writer_cpu_s_per_sim_s": None if writer_cpu is None
                    else round(writer_cpu / (n * loop.dt_control_s), 3),
                    "bytes_per_sim_s": round(record.stat().st_size / ((n + WARMUP_S / loop.dt_control_s)
                                                                      * loop.dt_control_s)),
                    "error": status["error"]})
    robot.close()
    return out


ROUNDS = 2  # the three runs in one order, then in the reverse one (the machine drifts between runs)


def _isolated_us(ticks: int = 1000, passes: int = 5) -> dict[str, float]:
    """A load-proof lower bound: the recorder alone fed `ticks` rows (and four setpoints every tick, every 4th
    tick, or never) in a tight loop, its CPU time per tick, the least of `passes` passes (warm caches: the loop's
    own work between two ticks is not there to evict them)."""
    from app.service.log_row import COLUMNS, ROW_LENGTH
    from app.service.session_recorder import SessionRecorder
    from app.service.setpoints import Setpoint, SetpointAck

    rng = np.random.default_rng(0)
    rows = rng.random((ticks, ROW_LENGTH))
    rows[:, [i for i, c in enumerate(COLUMNS) if c.endswith("/leg")]] = math.nan  # no footstep planned
    qpos = [rng.random(37) for _ in range(ticks)]
    sps = [Setpoint("rhand", (0.01, 0.0, 0.02), (0.0, 0.0, 0.0), seq=1), Setpoint("lhand", (0.01, 0.0, 0.0),
           (0.0, 0.0, 0.0), seq=1), Setpoint("head", (0.0, 0.0, 0.0), (0.0, 0.0, 0.1), seq=1),
           Setpoint("walk", (0.1, 0.0, 0.0), (0.0, 0.0, 0.0), seq=1)]
    acks = [SetpointAck(sp.point, 1, 0, 0.0) for sp in sps]
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        recorder = SessionRecorder(Path(tmp) / "isolated.mcap", {"dt_control_s": 0.005})
        for name, every in (("no_inputs", 0), ("inputs_at_50_hz", 4), ("inputs_every_tick", 1)):
            best = math.inf
            for _ in range(passes):
                c0 = time.thread_time()
                for k in range(ticks):
                    if every and k % every == 0:
                        recorder.setpoints("hook", 0.1, sps, acks)
                    recorder.tick(rows[k], qpos[k])
                best = min(best, (time.thread_time() - c0) / ticks)
            out[name] = round(best * 1e6, 2)
        recorder.close()
    return out


def _median(runs: list[dict], path: tuple[str, ...]) -> float:
    values = []
    for r in runs:
        for key in path:
            r = r[key]
        values.append(r)
    return round(float(np.median(values)), 2)


def run_recording_bench(duration_s: float = 5.0, scene: str = "default") -> dict[str, Any]:
    """The `record` scenario: the teleop walk as fast as possible without recording, with it (the four points'
    setpoints applied every tick), and with them at 50 Hz (every 4th tick, as the page streams); ROUNDS rounds
    in alternating order, medians reported."""
    runs: dict[str, list[dict]] = {"off": [], "on": [], "50hz": []}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(ROUNDS):
            order = ("off", "on", "50hz") if r % 2 == 0 else ("50hz", "on", "off")
            for mode in order:
                path = None if mode == "off" else Path(tmp) / f"bench-{r}-{mode}.mcap"
                runs[mode].append(_run(duration_s, scene, path, stream_every=4 if mode == "50hz" else 1))
    off, on, at_50_hz = runs["off"], runs["on"], runs["50hz"]
    return {
        "scenario": "record", "scene": scene, "sim_time_s": duration_s, "rounds": ROUNDS,
        "recording_per_tick_ms": round(_median(on, ("recording_per_tick_us",)) / 1e3, 5),
        "recording_per_tick_ms_inputs_at_50_hz": round(_median(at_50_hz, ("recording_per_tick_us",)) / 1e3, 5),
        "recording_per_tick_ms_each_round": [r["recording_per_tick_us"] / 1e3 for r in on],
        "timer_overhead_us": on[0]["timer_overhead_us"],
        "isolated_per_tick_us": _isolated_us(),
        "recorder_tick_cpu_us": on[-1]["recorder_tick"], "recorder_inputs_cpu_us": on[-1]["recorder_inputs"],
        "tick_cpu_mean_us": {name: _median(rs, ("tick_cpu", "mean_us")) for name, rs in
                             (("without", off), ("with", on), ("with_inputs_at_50_hz", at_50_hz))},
        "tick_cpu_p50_us": {name: _median(rs, ("tick_cpu", "p50_us")) for name, rs in
                            (("without", off), ("with", on), ("with_inputs_at_50_hz", at_50_hz))},
        "tick_wall_p50_us": {"without": _median(off, ("tick", "p50_us")), "with": _median(on, ("tick", "p50_us"))},
        "tick_cpu_without_us": off[-1]["tick_cpu"], "tick_cpu_with_us": on[-1]["tick_cpu"],
        "writer_cpu_s_per_sim_s": _median(on, ("writer_cpu_s_per_sim_s",)),
        "file_bytes_per_sim_s": on[-1]["bytes_per_sim_s"],
        "fallen": any(r["fallen"] for rs in runs.values() for r in rs),
        "error": next((r["error"] for rs in (on, at_50_hz) for r in rs if r["error"]), None),
        "note": "recording_per_tick_ms: the CPU time the recorder takes in the loop's thread (row and qpos copies, "
                "batches written to the pipe, inputs), timed where it is called (the timer's own overhead "
                "subtracted), summed and divided by the ticks; with four setpoints every tick, and at 50 Hz. "
                "tick_cpu: the loop thread's CPU time per tick (stream + step) in the same runs and in runs without "
                "recording (it also carries what the writer process and the other jobs on the 2 cores do to the "
                "loop's core and caches). isolated_per_tick_us: the recorder alone in a tight loop, warm, least "
                "of 5 passes (a lower bound the machine's load does not inflate)",
    }
