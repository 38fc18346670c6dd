"""Benchmark: run the chain synchronously as fast as possible on a scenario and report its timing."""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from app.lab.bench_cameras import CAMERA_SCENARIOS, run_camera_bench, run_recognition_bench, run_recognition_paced_bench
from app.lab.bench_scenarios import SCENARIOS
from app.service import OperatorService
from app.service.local import LocalRobot
from controller.core.chain import CHAIN_ORDER
from controller.core.loop import ControlLoop

#: Named layer selections for `run_bench(layers=...)`: the foundation chain of issue 2 (estimation, the
#: planned stream and the safety layers; es, ic, abc and st pass their input through).
CHAINS: dict[str, tuple[str, ...]] = {
    "full": CHAIN_ORDER,
    "foundation": ("kf", "rmfo", "seq", "co", "hes", "el"),
}


def layer_selection(layers: str | Sequence[str]) -> tuple[str, ...]:
    """A chain name of CHAINS or layer names (a sequence or "kf,rmfo,..."), checked against CHAIN_ORDER."""
    if isinstance(layers, str):
        if layers in CHAINS:
            return CHAINS[layers]
        layers = [name.strip() for name in layers.split(",") if name.strip()]
    names = tuple(layers)
    unknown = [name for name in names if name not in CHAIN_ORDER]
    if unknown or not names:
        raise ValueError(f"unknown layer(s) {unknown}; valid layers: {', '.join(CHAIN_ORDER)} "
                         f"(or a chain: {', '.join(CHAINS)})")
    return names


class _TouchRecorder:
    """Stands in for a layer's TickContext: every read or write goes through to the real one and marks the
    tick as used. A layer that passes its input through returns it without touching the context."""

    __slots__ = ("_ctx", "touched")

    def __init__(self, ctx) -> None:
        object.__setattr__(self, "_ctx", ctx)
        object.__setattr__(self, "touched", False)

    def __getattr__(self, name: str):
        object.__setattr__(self, "touched", True)
        return getattr(self._ctx, name)

    def __setattr__(self, name: str, value) -> None:
        object.__setattr__(self, "touched", True)
        setattr(self._ctx, name, value)


#: ticks `layers_that_ran` watches (after the timed part: the recorder would slow the layers it times)
PROBE_TICKS = 20


def layers_that_ran(loop: ControlLoop, ticks: int = PROBE_TICKS) -> set[str]:
    """Step the loop `ticks` times and return the layers whose tick used the tick's context (sensors,
    estimate, ports) or returned another reference than it was given, in any of those ticks. A disabled
    layer that honours its flag does neither (bookkeeping on the reference it passes on, as co and el do,
    is not counted); disabled, the KalmanFilter and the RemoveForceOffset still fill the estimate and the
    HardEmergencyStopper still publishes the hold port and would freeze the command on an e-stop.
    Meant for disabled layers: an enabled one may work on the reference alone, unseen here (the
    CollisionDetector checking the command)."""
    chain = loop.chain
    ran: set[str] = set()

    def watched_tick(ctx, ref):
        for name, layer in chain.layers.items():
            recorder = _TouchRecorder(ctx)
            out = layer.tick(recorder, ref)
            if recorder.touched or out is not ref:
                ran.add(name)
            ref = out
        return ref

    chain.tick = watched_tick  # this chain only, until restored below
    try:
        for _ in range(ticks):
            loop.step()
    finally:
        del chain.tick
    return ran


def _clear_timers(loop: ControlLoop) -> None:
    for timer in (*loop.chain.timers.values(), *loop.chain.after_write_timers.values(), loop.tick_timer,
                  loop.physics_timer, loop.read_to_write_timer, loop.after_write_timer):
        timer.clear()


def _percentiles(samples: np.ndarray) -> dict[str, float]:
    if samples.size == 0:
        return {"p50_ms": 0.0, "p99_ms": 0.0}
    return {"p50_ms": round(float(np.percentile(samples, 50)), 5),
            "p99_ms": round(float(np.percentile(samples, 99)), 5)}


def _summed(samples: dict[str, np.ndarray], names: Sequence[str], n: int) -> np.ndarray:
    total = np.zeros(n)
    for name in names:
        total += samples[name]
    return total


#: Benchmarks of the console as users run it (HTTP and the robot in their own processes), not of the chain.
CONSOLE_SCENARIOS = {
    "load": "the console at real time under 20 pollers of /api/state at 10 Hz, 100 commands/s and an e-stop "
            "pressed (and released) every second: tick start-lateness, /api/state and e-stop request times",
    "estop-browser": "E-STOP pointer-down in a real Chromium -> hard stop engaged in the loop, 50 clicks while the "
                     "page streams a stick (stubbed gamepad) and shows the 3D view: p50/p99/max [ms]",
    "page-rates": "the operator page in a real Chromium beside a console at real time: the camera and the plots' "
                  "update rates delivered (to a script) and shown (by the page, and viser's CP plot) over --duration "
                  "wall seconds [Hz] (asked: camera >= 10, plots >= 20)",
    "viewers": "the console at real time watched by 5 clients, each with the camera stream (12 Hz) and the 20 Hz "
               "telemetry, for --duration wall seconds (the issue asks 300): tick start-lateness p99 per 30 s "
               "window against 10 s unwatched before, and the rates each client received",
}


def run_load_bench(duration_s: float = 30.0, scene: str = "default") -> dict[str, Any]:
    """The `load` scenario: a real console (`hrp2-console --headless --speed 1.0`) under load."""
    from app.lab.console_process import Console, run_load

    console = Console("--speed", "1.0", "--scene", scene)
    try:
        report = run_load(console, duration_s, estop_every_s=1.0)
    finally:
        console.stop()
    return {"scenario": "load", "scene": scene, **report}


def run_bench(scenario: str = "stand", duration_s: float = 5.0, scene: str = "default",
              layers: str | Sequence[str] | None = None) -> dict[str, Any]:
    """Run `scenario` for `duration_s` of simulated time, synchronously, and return the timing report.

    `layers` (a chain name of CHAINS or layer names) keeps only those layers working: the others are
    disabled (`enabled = False`). The labels say what ran, watched after the timed part
    (`layers_that_ran`): "chain" and "layers" are the enabled layers and the disabled ones that kept
    working ("disabled_but_ran", e.g. kf and hes), "passthrough" the disabled ones that passed their
    input through, with their timers. The report then also gives the whole step's wall time less physics
    (`step_ms`: chain, snapshot, state estimation, logging) and the loop's own share of it
    (`loop_overhead_ms`: step minus the sum of all layer timers and the after-write work).

    `tick_ms` (the step less physics) is split at the write: `read_to_write_ms`, sensor read to command written
    (the sensor-to-actuator path: the layers' ticks), and `after_write_ms`, the layers' work once the command is out
    (Layer.after_write: the next tick's preparation; per layer in `after_write_layers`)."""
    if scenario in CAMERA_SCENARIOS:
        if layers is not None:
            raise ValueError(f"scenario {scenario!r} times the cameras; --layers/--chain do not apply")
        if scenario == "recognition-paced":
            return run_recognition_paced_bench(duration_s)
        return run_camera_bench() if scenario == "camera" else run_recognition_bench()
    if scenario == "record":
        if layers is not None:
            raise ValueError("scenario 'record' times the recording on the whole chain; --layers/--chain do not apply")
        from app.lab.bench_recording import run_recording_bench

        return run_recording_bench(duration_s, scene)
    if scenario in CONSOLE_SCENARIOS:
        if layers is not None:
            raise ValueError(f"scenario {scenario!r} runs the whole console; --layers/--chain do not apply")
        if scenario == "estop-browser":
            from app.lab.bench_browser import run_estop_browser_bench

            return run_estop_browser_bench(scene=scene)
        if scenario == "page-rates":
            from app.lab.bench_browser import run_page_rates_bench

            return run_page_rates_bench(duration_s, scene=scene)
        if scenario == "viewers":
            from app.lab.bench_viewers import run_viewers_bench

            return run_viewers_bench(duration_s, scene=scene)
        return run_load_bench(duration_s, scene)
    if scenario not in SCENARIOS:
        valid = ", ".join((*SCENARIOS, *CONSOLE_SCENARIOS, *CAMERA_SCENARIOS, "record"))
        raise ValueError(f"unknown scenario {scenario!r}; valid scenarios: {valid}")
    spec = SCENARIOS[scenario]
    selected = None if layers is None else layer_selection(layers)
    if selected is not None and not set(spec.needs) <= set(selected):
        raise ValueError(f"scenario {scenario!r} needs the layer(s) {', '.join(spec.needs)}")
    robot = LocalRobot(scene=scene, speed=None)
    service = OperatorService(robot)
    loop = robot.loop
    disabled = []
    if selected is not None:
        disabled = [name for name in loop.chain.order() if name not in selected]
        service.enable_layers({name: False for name in disabled})
    if spec.warmup_s > 0.0:
        loop.run_for(spec.warmup_s)  # not part of the report
    spec.setup(service)
    n = max(1, int(round(duration_s / loop.dt_control_s)))
    names = loop.chain.order()
    step_ms = np.empty(n)
    watched = np.zeros(n, dtype=bool)
    tick_ms = np.empty(n)
    physics_ms = np.empty(n)
    read_to_write_ms = np.empty(n)
    after_write_ms = np.empty(n)
    layer_ms = {name: np.empty(n) for name in names}
    after_write_layer_ms = {name: [] for name in loop.chain.after_write_timers}  # (no sample after a faulted tick)
    timers = [loop.tick_timer, loop.physics_timer, loop.read_to_write_timer, loop.after_write_timer,
              *(loop.chain.timers[name] for name in names)]
    outputs = [tick_ms, physics_ms, read_to_write_ms, after_write_ms, *(layer_ms[name] for name in names)]
    chunk = min(t.capacity for t in timers)  # ticks the timers' ring buffers hold
    clock = time.perf_counter
    step = loop.step
    wall_s = 0.0
    for first in range(0, n, chunk):  # the timers keep the samples: nothing copied between ticks
        last = min(n, first + chunk)
        _clear_timers(loop)
        t0 = clock()
        stream = spec.stream
        for i in range(first, last):
            if stream is not None:
                stream(robot)
            t_step = clock()
            step()
            step_ms[i] = (clock() - t_step) * 1e3
            if spec.watch is not None:
                watched[i] = spec.watch[1](loop.snapshot)
        wall_s += clock() - t0
        for timer, out in zip(timers, outputs, strict=True):
            out[first:last] = timer.samples()
        for name, samples in after_write_layer_ms.items():
            samples.append(loop.chain.after_write_timers[name].samples())
    tick_ms -= physics_ms  # the controller's share
    step_ms -= physics_ms
    snap = loop.snapshot
    fallen = bool(robot.host.observation.fallen)
    sim_s = n * loop.dt_control_s  # the timed part only (no warm-up)
    ran = layers_that_ran(loop) if disabled else set()  # (a few more ticks, not timed)
    passthrough = [name for name in disabled if name not in ran]
    working = [name for name in names if name not in passthrough]
    report = {
        "scenario": scenario,
        "scene": scene,
        "chain": " -> ".join(working),
        "ticks": n,
        "sim_time_s": round(sim_s, 6),
        "wall_time_s": round(wall_s, 4),
        "real_time_factor": round(sim_s / wall_s, 3) if wall_s > 0 else float("inf"),
        "tick_ms": _percentiles(tick_ms),
        # the tick split at the write: what the command waits for, and the work done once it is out (after_write)
        "read_to_write_ms": _percentiles(read_to_write_ms),
        "after_write_ms": _percentiles(after_write_ms),
        "physics_ms": _percentiles(physics_ms),
        "layers": {name: _percentiles(layer_ms[name]) for name in working},
        "after_write_layers": {name: _percentiles(np.concatenate(samples))
                               for name, samples in after_write_layer_ms.items() if name in working},
        "fallen": fallen,
        "fault": snap.fault,
    }
    if spec.watch is not None:
        for label, mask in ((spec.watch[0], watched), ("other", ~watched)):
            report[label] = {"ticks": int(mask.sum()), "tick_ms": _percentiles(tick_ms[mask]),
                             "read_to_write_ms": _percentiles(read_to_write_ms[mask]),
                             "after_write_ms": _percentiles(after_write_ms[mask]),
                             "layers": {name: _percentiles(layer_ms[name][mask]) for name in working}}
    if selected is not None:
        report["disabled_but_ran"] = [name for name in disabled if name in ran]
        report["passthrough"] = {name: _percentiles(layer_ms[name]) for name in passthrough}
        report["step_ms"] = _percentiles(step_ms)
        report["layers_sum_ms"] = _percentiles(_summed(layer_ms, working, n))
        report["loop_overhead_ms"] = _percentiles(step_ms - _summed(layer_ms, names, n) - after_write_ms)
    return report
