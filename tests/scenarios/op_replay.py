"""The operation layer alone on the recorded inputs of `hrp2-console bench --scenario teleop`: a load-proof
timing (each tick's least over N replays into fresh layers) and a digest of everything the layer put out, so a
refactor of the layer can prove it changed neither its results nor (for the worse) its cost.

    python -m tests.scenarios.op_replay record FILE [--duration 5]   # the bench's run, the layer's inputs kept
    python -m tests.scenarios.op_replay time FILE [--repeats 5]      # per-tick least over the replays [ms]
    python -m tests.scenarios.op_replay digest FILE                  # sha256 of outputs, ports, status, views

The recording holds every call the loop made into the layer (commands at the boundaries, ticks with their
context and input reference) from the robot's start: the warm-up's idle ticks, then the operated ones."""

from __future__ import annotations

import argparse
import copy
import hashlib
import json
import pickle
import time
from pathlib import Path

import numpy as np

_COMMANDS = ("set_params", "set_motion", "drop_motion", "set_behavior", "reset_targets")


def record(path: Path, duration_s: float) -> None:
    """Run the teleop bench's scenario (warm-up, then `duration_s` of streamed setpoints) and keep every call
    the loop made into its operation layer."""
    from app.lab.bench_scenarios import SCENARIOS
    from app.service import OperatorService
    from app.service.local import LocalRobot
    from controller.core.types import Ports

    spec = SCENARIOS["teleop"]
    robot = LocalRobot(scene="default", speed=None)
    service = OperatorService(robot)
    loop = robot.loop
    op = loop.chain["op"]
    calls: list = []

    def wrap(name):
        original = getattr(op, name)

        def recorded(*args, **kwargs):
            calls.append((name, copy.deepcopy(args), copy.deepcopy(kwargs)))
            return original(*args, **kwargs)
        setattr(op, name, recorded)

    for name in _COMMANDS:
        wrap(name)
    tick = op.tick

    def recorded_tick(ctx, ref):
        kept = copy.copy(ctx)
        kept.ports = Ports()  # what the layer publishes is the replay's own
        calls.append(("tick", copy.deepcopy((kept, ref)), {}))
        return tick(ctx, ref)
    op.tick = recorded_tick
    loop.run_for(spec.warmup_s)
    spec.setup(service)
    for _ in range(int(round(duration_s / loop.dt_control_s))):
        spec.stream(robot)
        loop.step()
    path.write_bytes(pickle.dumps({"dt_s": loop.dt_control_s, "calls": calls}))
    print(f"{sum(c[0] == 'tick' for c in calls)} ticks, {len(calls)} calls -> {path}")


def _fresh(recording: dict):
    from controller.layers.operation import OperationLayer

    return OperationLayer(recording["dt_s"])


def replay(recording: dict, op, on_tick=None) -> np.ndarray:
    """All calls into `op`; returns each tick's wall time [ms]. on_tick(op, ctx, out) after each tick (not timed)."""
    ticks = [c for c in recording["calls"] if c[0] == "tick"]
    ms = np.empty(len(ticks))
    clock = time.perf_counter
    k = 0
    for name, args, kwargs in recording["calls"]:
        if name != "tick":
            getattr(op, name)(*args, **kwargs)
            continue
        ctx, ref = copy.copy(args[0]), args[1]
        ctx.ports = type(ctx.ports)()
        t0 = clock()
        out = op.tick(ctx, ref)
        ms[k] = (clock() - t0) * 1e3
        if on_tick is not None:
            on_tick(op, ctx, out)
        k += 1
    return ms


def timing(recording: dict, repeats: int) -> dict:
    """Each tick's least over `repeats` replays into fresh layers (what the machine's other jobs add drops
    out), its status read after it the same way; split into the idle and the operated ticks."""
    status_ms: list[np.ndarray] = []
    tick_ms = []
    for _ in range(repeats):
        op = _fresh(recording)
        times: list[float] = []

        def read_status(op, ctx, out, times=times):
            t0 = time.perf_counter()
            op.status()
            times.append((time.perf_counter() - t0) * 1e3)
        tick_ms.append(replay(recording, op, read_status))
        status_ms.append(np.array(times))
    least, least_status = np.min(tick_ms, axis=0), np.min(status_ms, axis=0)
    operated = np.array([c[1][0].time_s for c in recording["calls"] if c[0] == "tick"]) >= _first_operated(recording)
    report = {}
    for label, mask in (("operated", operated), ("idle", ~operated)):
        t, s = least[mask], least_status[mask]
        report[label] = {"ticks": int(mask.sum()), "tick_p50_ms": round(float(np.median(t)), 4),
                         "tick_p99_ms": round(float(np.percentile(t, 99)), 4),
                         "status_p50_ms": round(float(np.median(s)), 4)}
    return report


def _first_operated(recording: dict) -> float:
    """Control time [s] of the first streamed setpoint (the idle warm-up ends there)."""
    return min(c[1][2] for c in recording["calls"] if c[0] == "set_motion")


def digest(recording: dict) -> str:
    """sha256 over every tick's output reference, published walk command, status document and (every 10th
    tick) view: the layer's results bit for bit."""
    h = hashlib.sha256()

    def feed(op, ctx, out):
        for a in (out.q_rad, out.base_pos_world, out.base_rpy_rad):
            h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
        h.update(repr(ctx.ports.walk_command).encode())
        h.update(json.dumps(op.status().to_dict(), sort_keys=True).encode())
        if ctx.tick % 10 == 0:
            v = op.view()
            h.update(repr((v.time_s, v.feet_yaw_rad, v.gaze_rad, v.waist_height_m, v.walking, v.motion_stopped,
                           v.collision_pairs, v.lsole_from_rsole)).encode())
            for pose in (v.feet_p_world_m, *(a for p in v.points.values() for a in (
                    p.p_world_m, p.R_world_point, p.p_feet_m, p.R_feet_point))):
                h.update(np.ascontiguousarray(pose, dtype=np.float64).tobytes())
    replay(recording, _fresh(recording), feed)
    return h.hexdigest()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("what", choices=("record", "time", "digest"))
    p.add_argument("file", type=Path)
    p.add_argument("--duration", type=float, default=5.0, help="record: the timed part's simulated seconds")
    p.add_argument("--repeats", type=int, default=5, help="time: replays; each tick's least is kept")
    args = p.parse_args()
    if args.what == "record":
        record(args.file, args.duration)
        return
    recording = pickle.loads(args.file.read_bytes())
    if args.what == "time":
        print(json.dumps(timing(recording, args.repeats)))
    else:
        print(digest(recording))


if __name__ == "__main__":
    main()
