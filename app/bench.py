"""Benchmark: run the chain synchronously as fast as possible on a scenario and report its timing."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.runtime import Runtime
from controller.loop import ControlLoop
from robot.names import JOINT_NAMES

#: HRP-2 half-sitting [deg], JOINT_NAMES order (the plant's "home" keyframe).
HALF_SITTING_DEG = np.array(
    [0, 0, -26, 50, -24, 0] * 2 + [0, 0, 0, 0] + [15, -10, 0, -30, 0, 0, 10] + [15, 10, 0, -30, 0, 0, 10],
    dtype=float,
)


@dataclass(frozen=True)
class Scenario:
    """What the robot does during a benchmark: `setup(loop)` queues its commands before the first timed
    tick, after `warmup_s` of untimed standing (the AutoBalancer and the Stabilizer blend in)."""

    description: str
    setup: Callable[[ControlLoop], None]
    warmup_s: float = 0.0


def _stand(loop: ControlLoop) -> None:
    """Nothing to send: the chain holds the half-sitting posture it started in."""


def _arms(loop: ControlLoop) -> None:
    """Both arms forward with the elbows bent and back, over and over (setJointAngles sequence)."""
    q_fwd = HALF_SITTING_DEG.copy()
    for name, deg in (("RARM_JOINT0", -50), ("RARM_JOINT3", -70), ("LARM_JOINT0", -50), ("LARM_JOINT3", -70)):
        q_fwd[JOINT_NAMES.index(name)] = deg
    poses = [np.deg2rad(q_fwd), np.deg2rad(HALF_SITTING_DEG)] * 30
    loop.call(lambda: loop.chain["seq"].set_joint_angles_sequence(poses, [1.5] * len(poses)))


def _walk(loop: ControlLoop) -> None:
    """goVelocity(0.1 m/s forward) for the whole timed part (the AutoBalancer is running by then)."""
    loop.call(lambda: loop.chain["abc"].go_velocity(0.1, 0.0, 0.0))


#: Benchmark scenarios by name.
SCENARIOS: dict[str, Scenario] = {
    "stand": Scenario("hold half-sitting", _stand),
    "arms": Scenario("arms forward and back with setJointAngles (SequencePlayer interpolating)", _arms),
    "walk": Scenario("goVelocity(0.1 m/s, 0, 0) after 2.5 s of standing (not timed)", _walk, warmup_s=2.5),
}


def _clear_timers(loop: ControlLoop) -> None:
    for timer in (*loop.chain.timers.values(), loop.tick_timer, loop.physics_timer):
        timer.clear()


def _percentiles(samples: np.ndarray) -> dict[str, float]:
    if samples.size == 0:
        return {"p50_ms": 0.0, "p99_ms": 0.0}
    return {"p50_ms": round(float(np.percentile(samples, 50)), 5),
            "p99_ms": round(float(np.percentile(samples, 99)), 5)}


def run_bench(scenario: str = "stand", duration_s: float = 5.0, scene: str = "default") -> dict[str, Any]:
    """Run `scenario` for `duration_s` of simulated time, synchronously, and return the timing report."""
    if scenario not in SCENARIOS:
        raise ValueError(f"unknown scenario {scenario!r}; valid scenarios: {', '.join(SCENARIOS)}")
    runtime = Runtime(scene=scene, speed=None)
    loop = runtime.loop
    spec = SCENARIOS[scenario]
    if spec.warmup_s > 0.0:
        loop.run_for(spec.warmup_s)  # not part of the report
        _clear_timers(loop)
    spec.setup(loop)
    n = max(1, int(round(duration_s / loop.dt_control_s)))
    tick_ms = np.empty(n)
    physics_ms = np.empty(n)
    layer_ms = {name: np.empty(n) for name in loop.chain.order()}
    t0 = time.perf_counter()
    for i in range(n):
        loop.step()
        tick_ms[i] = loop.tick_timer.last_ms - loop.physics_timer.last_ms  # the controller's share
        physics_ms[i] = loop.physics_timer.last_ms
        for name, timer in loop.chain.timers.items():
            layer_ms[name][i] = timer.last_ms
    wall_s = time.perf_counter() - t0
    snap = loop.snapshot
    sim_s = n * loop.dt_control_s  # the timed part only (no warm-up)
    return {
        "scenario": scenario,
        "scene": scene,
        "chain": loop.chain.describe(),
        "ticks": n,
        "sim_time_s": round(sim_s, 6),
        "wall_time_s": round(wall_s, 4),
        "real_time_factor": round(sim_s / wall_s, 3) if wall_s > 0 else float("inf"),
        "tick_ms": _percentiles(tick_ms),
        "physics_ms": _percentiles(physics_ms),
        "layers": {name: _percentiles(v) for name, v in layer_ms.items()},
        "fallen": bool(snap.fallen),
        "fault": snap.fault,
    }
