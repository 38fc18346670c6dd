"""Verbs of the simulation and its loop: push, place an object, reset, inject a fault; the robot's info,
the loop's timing; shutdown and the in-process `Call`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.service.errors import InvalidArgument, NotFound
from app.service.verbs.base import MIN_MOTION_TIME_S, Host, RobotInfo, Verb, check_bounded, check_finite

MAX_PUSH_FORCE_N = 2000.0  # [N]
MAX_PUSH_DURATION_S = 5.0  # [s]
MAX_OBJECT_XY_M = 10.0  # [m] |x|, |y| where a scene object may be placed
MAX_OBJECT_Z_M = 3.0  # [m] highest body origin of a placed object (z >= 0)


@dataclass(frozen=True)
class Push(Verb):
    """Apply a world-frame force [N] at a body's COM for `duration_s` (a simulator operation)."""

    name = "push"
    body: str
    force_n: tuple[float, float, float]
    duration_s: float

    def __post_init__(self) -> None:
        check_finite("force", self.force_n)
        magnitude = float(np.linalg.norm(self.force_n))
        if magnitude > MAX_PUSH_FORCE_N:
            raise InvalidArgument("force", f"magnitude {magnitude:.1f} N is above the allowed {MAX_PUSH_FORCE_N:g} N")
        check_bounded("duration", self.duration_s, MIN_MOTION_TIME_S, MAX_PUSH_DURATION_S, "s")

    def check(self, info: RobotInfo) -> None:
        if self.body not in info.bodies:
            raise NotFound(f"body: unknown body {self.body!r}; valid bodies: {', '.join(info.bodies)}")

    def run(self, host: Host) -> str:
        host.plant.push(self.body, np.array(self.force_n), self.duration_s)
        return f"pushing {self.body} for {self.duration_s:g} s"


@dataclass(frozen=True)
class PlaceObject(Verb):
    """Put a scene object at (x, y) standing on what is below it, or with its body origin at (x, y, z) [m, world],
    yawed by `yaw_rad`, at rest (a simulator operation: the robot learns of it only through its cameras)."""

    name = "place_object"
    object_name: str
    position_m: tuple[float, ...]
    yaw_rad: float = 0.0

    def __post_init__(self) -> None:
        if len(self.position_m) not in (2, 3):
            raise InvalidArgument("position", f"must be [x, y] or [x, y, z] [m], got {len(self.position_m)} numbers")
        check_finite("position", self.position_m)
        for axis, value in zip("xy", self.position_m[:2], strict=False):
            check_bounded(f"position.{axis}", value, -MAX_OBJECT_XY_M, MAX_OBJECT_XY_M, "m")
        if len(self.position_m) == 3:
            check_bounded("position.z", self.position_m[2], 0.0, MAX_OBJECT_Z_M, "m")
        check_bounded("yaw", self.yaw_rad, -2 * math.pi, 2 * math.pi, "deg", math.degrees)

    def check(self, info: RobotInfo) -> None:
        if self.object_name not in info.objects:
            valid = ", ".join(info.objects) or f"none in scene {info.scene!r}"
            raise NotFound(f"object: unknown object {self.object_name!r}; valid objects: {valid}")

    def run(self, host: Host) -> tuple[float, float, float]:
        placed = host.plant.place_object(self.object_name, self.position_m, self.yaw_rad)
        return tuple(float(v) for v in placed)


@dataclass(frozen=True)
class Reset(Verb):
    """Restart the simulation and the controller chain (optionally in another scene)."""

    name = "reset"
    scene: str | None = None

    def check(self, info: RobotInfo) -> None:
        if self.scene is not None and self.scene not in info.scenes:
            raise InvalidArgument("scene", f"unknown scene {self.scene!r}; available scenes: {', '.join(info.scenes)}")

    def run(self, host: Host) -> str:
        host.reset(self.scene)
        return f"simulation reset (scene {host.scene!r})"


@dataclass(frozen=True)
class InjectFault(Verb):
    """Test hook, reachable from Python, and over HTTP (POST /api/sim/fault) only on a console started with
    HRP2_TEST_HOOKS=1: `kind` "layer" makes `layer`'s tick raise from now on (until a reset builds a new chain);
    "nan" starts the next physics step from a NaN velocity."""

    kind: str
    layer: str = "st"
    name = "inject_fault"

    def run(self, host: Host) -> str:
        return host.inject_fault(self.kind, self.layer)


@dataclass(frozen=True)
class GetInfo(Verb):
    name = "get_info"
    recorded = False

    def run(self, host: Host) -> RobotInfo:
        return host.info()


@dataclass(frozen=True)
class ChainTiming(Verb):
    """The layer order and the per-layer, whole-tick and physics p50/p99 times [ms]."""

    name = "chain_timing"
    recorded = False

    def run(self, host: Host) -> dict:
        loop = host.loop
        c = loop.chain
        return {"order": c.order(), "chain": c.describe(), "timing": c.timing(),
                "tick_ms": loop.tick_timer.percentiles(), "physics_ms": loop.physics_timer.percentiles()}


@dataclass(frozen=True)
class GetLoopTiming(Verb):
    """The loop's lateness figures over the last `last_s` seconds of ticks (and whole 1-s windows)."""

    name = "get_loop_timing"
    recorded = False
    last_s: float = 60.0

    def __post_init__(self) -> None:
        check_bounded("last_s", self.last_s, 0.005, 3600.0, "s")

    def run(self, host: Host):
        loop = host.loop
        ticks = max(1, int(round(self.last_s / loop.dt_control_s)))
        return loop.lateness.summary(last_ticks=ticks, last_windows=int(self.last_s))


@dataclass(frozen=True)
class Shutdown(Verb):
    """Stop the loop after this boundary; the result is the run's summary."""

    name = "shutdown"
    recorded = False

    def run(self, host: Host) -> dict:
        host.stop_loop()
        return host.stats.summary()


@dataclass(frozen=True)
class Call(Verb):
    """Run `fn(host)` at a tick boundary: for tests and in-process tools only (a function cannot cross to
    the robot process unless it can be pickled)."""

    name = "call"
    fn: Any = field(compare=False)

    def run(self, host: Host) -> Any:
        return self.fn(host)
