"""The chain order, written once, and the object that runs the layers in that order."""

from __future__ import annotations

import time
from array import array
from collections.abc import Mapping

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.layer import Layer
from controller.core.types import Ports, Reference, TickContext

#: The order of the real-time layers ([MLC] Fig. 3, hrpsys getJointAngleControllerList).
#: kf: KalmanFilter, rmfo: RemoveForceOffset, seq: SequencePlayer, op: OperationLayer ([OP] Eq. 5),
#: es: EmergencyStopper, ic: ImpedanceController, abc: AutoBalancer, st: Stabilizer, co: CollisionDetector,
#: hes: HardEmergencyStopper, el: SoftErrorLimiter. Layers not built yet are skipped.
CHAIN_ORDER: tuple[str, ...] = ("kf", "rmfo", "seq", "op", "es", "ic", "abc", "st", "co", "hes", "el")

_TIMING_WINDOW = 4096  # ticks kept per layer for p50 / p99


class TickTimer:
    """Ring buffer of tick durations [ms] for one layer (a C array of doubles: `add` runs a dozen times
    per tick, and storing a float in it costs less than in a numpy array)."""

    __slots__ = ("_buf", "_size", "_n", "last_ms")

    def __init__(self, size: int = _TIMING_WINDOW) -> None:
        self._buf = array("d", bytes(8 * size))  # zeros
        self._size = size
        self._n = 0
        self.last_ms = 0.0

    @property
    def capacity(self) -> int:
        """How many of the last durations are kept."""
        return self._size

    def add(self, ms: float) -> None:
        self._buf[self._n % self._size] = ms
        self._n += 1
        self.last_ms = ms

    def samples(self) -> np.ndarray:
        return np.frombuffer(self._buf, dtype=float, count=min(self._n, self._size)).copy()

    def percentiles(self) -> dict[str, float]:
        s = self.samples()
        if s.size == 0:
            return {"p50_ms": 0.0, "p99_ms": 0.0, "n": 0}
        return {"p50_ms": float(np.percentile(s, 50)), "p99_ms": float(np.percentile(s, 99)), "n": int(s.size)}

    def clear(self) -> None:
        self._n = 0


class Chain:
    """Runs the present layers in CHAIN_ORDER, timing each one."""

    def __init__(self, layers: Mapping[str, Layer]) -> None:
        unknown = sorted(set(layers) - set(CHAIN_ORDER))
        if unknown:
            raise InvalidCommand(f"unknown layer name(s) {unknown}; the chain knows {list(CHAIN_ORDER)}")
        for name, layer in layers.items():
            if layer.name != name:
                raise InvalidCommand(f"layer registered as {name!r} calls itself {layer.name!r}")
        self.layers: dict[str, Layer] = {n: layers[n] for n in CHAIN_ORDER if n in layers}
        self.timers: dict[str, TickTimer] = {n: TickTimer() for n in self.layers}
        #: the layers with after-write work (Layer.after_write overridden): the loop calls nothing for the others
        self._after_write = [(n, layer) for n, layer in self.layers.items()
                             if type(layer).after_write is not Layer.after_write]
        #: their after-write work [ms] per call (0 when disabled), apart from their tick's timers
        self.after_write_timers: dict[str, TickTimer] = {n: TickTimer() for n, _ in self._after_write}
        stops = [layer for layer in self.layers.values() if layer.safe_stop]
        if len(stops) > 1:
            raise InvalidCommand(f"more than one safe-stop layer: {[s.name for s in stops]}")
        #: the layer faults and falls engage (the HardEmergencyStopper), None if the chain has none
        self.safe_stop_layer: Layer | None = stops[0] if stops else None

    def order(self) -> list[str]:
        return list(self.layers)

    def describe(self) -> str:
        """The chain as hrpsys prints it: `kf -> rmfo -> seq -> co -> hes -> el`."""
        return " -> ".join(self.layers)

    def __getitem__(self, name: str) -> Layer:
        try:
            return self.layers[name]
        except KeyError:
            raise InvalidCommand(f"no layer {name!r}; present: {self.order()}") from None

    def __contains__(self, name: str) -> bool:
        return name in self.layers

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        clock = time.perf_counter
        for name, layer in self.layers.items():
            t0 = clock()
            ref = layer.tick(ctx, ref)
            self.timers[name].add((clock() - t0) * 1e3)
        return ref

    def after_write(self, ports: Ports) -> None:
        """Each enabled layer's after-write work (Layer.after_write) in chain order, on this tick's `ports`."""
        clock = time.perf_counter
        timers = self.after_write_timers
        for name, layer in self._after_write:
            if not layer.enabled:
                timers[name].add(0.0)  # one sample per call for every timer: the bench lines them up by tick
                continue
            t0 = clock()
            layer.after_write(ports)
            timers[name].add((clock() - t0) * 1e3)

    def timing(self) -> dict[str, dict[str, float]]:
        return {n: t.percentiles() for n, t in self.timers.items()}
