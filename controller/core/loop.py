"""The fixed-rate control loop: one door in (a command queue drained at tick boundaries), immutable
snapshots out, paced to wall time or run as fast as possible with the same trajectory either way."""

from __future__ import annotations

import logging
import queue
import threading
import time
import traceback
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from controller.core.chain import Chain, TickTimer
from controller.core.errors import InvalidCommand
from controller.core.layer import Status
from controller.core.loop_timing import LatenessMeter, LoopTiming
from controller.core.types import Estimate, OdometryEstimate, Ports, Reference, TickContext, frozen_array
from robot.sensors import Sensors

log = logging.getLogger(__name__)


class Plant(Protocol):
    """The hardware interface the loop drives (robot.plant.MujocoPlant, or a real robot): its sensors, its
    servos, its clock. Nothing of a simulator's ground truth: the controller works from what it senses."""

    dt_physics: float

    @property
    def time_s(self) -> float: ...
    def read(self) -> Sensors: ...
    def write(self, q_ref_rad: np.ndarray) -> None: ...
    def step(self, n: int = 1) -> None: ...


class FallCheck(Protocol):
    """The loop's fall detector (controller.balance.fall_detector.FallDetector, which the system injects): fed the
    estimate of every tick; `reason` None until it finds a fall, then why, latched."""

    reason: str | None

    def check(self, est: Estimate, dt_s: float) -> str | None: ...


@dataclass(frozen=True, slots=True)
class Safety:
    """The loop's own safety state: the hard e-stop, a controller fault, a detected fall."""

    hard_stop: bool  # the HardEmergencyStopper is engaged
    hard_stop_reason: str | None  # "operator" | "fault" | "fallen"
    fault: str | None  # the last exception inside the chain ("Type: message"), until cleared
    fall: str | None  # why the FallDetector says the robot has fallen (latched until a reset)
    #: engaged, the command not frozen yet: "landing the step" (HardEmergencyStopperStatus.stopping); None: frozen
    hard_stop_stopping: str | None = None


@dataclass(frozen=True, slots=True)
class Snapshot:
    """Everything published after one tick. Immutable: readers may keep it as long as they like."""

    tick: int
    time_s: float
    q_cmd_rad: np.ndarray  # (30,) final command written to the servos
    q_seq_rad: np.ndarray  # (30,) the planned stream (SequencePlayer output)
    q_meas_rad: np.ndarray  # (30,) encoders
    reference: Reference  # the final reference (base pose, zmp, wrenches) after the last layer
    base_rpy_est_rad: np.ndarray  # (3,) KalmanFilter attitude
    wrenches_ext: np.ndarray  # (4, 6) RemoveForceOffset output, sensor frame
    cog_world: np.ndarray  # (3,) estimated from encoders + attitude [m]
    zmp_world: np.ndarray  # (3,) estimated from the foot F/T sensors [m]
    layers: dict[str, Status]  # per-layer frozen status
    layer_tick_ms: dict[str, float]  # wall time of each layer's tick [ms]
    safety: Safety
    loop_ms: float  # wall time of the whole tick (chain + physics) [ms]
    #: leg odometry: the feet and the controller's frame in the world (controller.balance.leg_odometry); None
    #: when no state estimator ran
    odometry: OdometryEstimate | None = None

    @property
    def fault(self) -> str | None:
        return self.safety.fault


StateEstimatorFn = Callable[[Sensors, Estimate, Reference], tuple[np.ndarray, np.ndarray]]


class ControlLoop:
    """Runs the chain every `dt_control_s` against a plant.

    Synchronous use (tests, scenarios, benchmarks): `step()`, `run_for(s)`, `run_until(pred)`.
    Threaded use (the console): `start(speed)` / `stop()`; commands through `submit(fn)`.
    A command is a callable run inside the loop at a tick boundary; its result or exception goes to
    the returned Future. An exception inside the chain is a fault: the loop holds the last command,
    engages the hard e-stop when present, reports the fault, and keeps running.
    """

    def __init__(self, plant: Plant, chain_factory: Callable[[Sensors, float], Chain],
                 dt_control_s: float = 0.005,
                 state_estimator: StateEstimatorFn | None = None,
                 on_snapshot: Callable[[Snapshot], None] | None = None,
                 fall_detector_factory: Callable[[], FallCheck] | None = None,
                 before_tick: Callable[[float], None] | None = None) -> None:
        if dt_control_s <= 0:
            raise InvalidCommand(f"dt_control_s must be > 0, got {dt_control_s}")
        self._chain_factory = chain_factory
        self._state_estimator = state_estimator
        self._on_snapshot = on_snapshot
        self.dt_control_s = float(dt_control_s)
        self._queue: queue.SimpleQueue[tuple[Callable[[], Any], Future]] = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._stop_event = threading.Event()
        self._pacing = False  # run_paced is ticking (in its own thread or the caller's)
        self.speed: float | None = 1.0
        self.tick_timer = TickTimer()
        self.physics_timer = TickTimer()
        #: [ms] sensor read to command written (the chain, the fall check): what actuation waits for
        self.read_to_write_timer = TickTimer()
        #: [ms] the layers' after-write work (Layer.after_write), after the command is out: not on that path
        self.after_write_timer = TickTimer()
        self.lateness = LatenessMeter()
        self.resets = 0  # replace_plant calls: a paced run starts a new schedule at each
        self.nap_s = 0.0  # [s] run_paced waits for the next tick in naps this long (0: one sleep)
        self.due_s: float | None = None  # [s] time.perf_counter() at which the awaited tick is due (paced waits)
        self._fall_detector_factory = fall_detector_factory
        #: called with the control time [s] at the start of every step(), after the command queue is drained
        #: (behaviours and the operator's streamed setpoints step here); an exception is logged, never fatal
        self.before_tick: Callable[[float], None] | None = before_tick
        self._attach(plant)

    # ---- construction / reset -------------------------------------------------------------
    def _attach(self, plant: Plant) -> None:
        substeps = self.dt_control_s / plant.dt_physics
        if abs(substeps - round(substeps)) > 1e-9 or round(substeps) < 1:
            raise InvalidCommand(
                f"control period {self.dt_control_s} s must be a whole multiple of the physics step "
                f"{plant.dt_physics} s"
            )
        self.plant = plant
        self.substeps = int(round(substeps))
        sensors = plant.read()
        self.chain = self._chain_factory(sensors, self.dt_control_s)
        self.tick_count = 0
        self.fault: str | None = None
        self.fall = None if self._fall_detector_factory is None else self._fall_detector_factory()
        self._ports = Ports()
        self._last_ref = Reference.from_arrays(sensors.q_rad)
        self._last_q_cmd = np.array(sensors.q_rad, dtype=float)
        self.snapshot: Snapshot = self._make_snapshot(sensors, Estimate(), self._last_ref, 0.0, sensors.q_rad)

    def replace_plant(self, plant: Plant) -> None:
        """Swap in a new plant (simulation reset) and rebuild the chain from its sensors."""
        self._attach(plant)
        self.resets += 1

    # ---- commands -------------------------------------------------------------------------
    def submit(self, fn: Callable[[], Any]) -> Future:
        """Queue `fn` to run at the next tick boundary; returns a Future with its result."""
        fut: Future = Future()
        self._queue.put((fn, fut))
        if not self.running:
            # Nobody is ticking in the background: run it now, still between ticks.
            self._drain()
        return fut

    def call(self, fn: Callable[[], Any], timeout_s: float = 5.0) -> Any:
        """Submit and wait for the result (re-raising the command's exception)."""
        return self.submit(fn).result(timeout=timeout_s)

    def _drain(self) -> None:
        q = self._queue
        while not q.empty():  # (cheaper than get_nowait raising Empty on the usual empty queue)
            try:
                fn, fut = q.get_nowait()
            except queue.Empty:  # another thread drained it meanwhile
                return
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                fut.set_result(fn())
            except BaseException as exc:  # noqa: BLE001 - a command never kills the loop
                fut.set_exception(exc)

    # ---- one tick -------------------------------------------------------------------------
    def step(self) -> Snapshot:
        t_start = time.perf_counter()
        self._drain()
        hook = self.before_tick
        if hook is not None:
            try:
                hook(self.plant.time_s)
            except Exception:  # noqa: BLE001 - a behaviour or a setpoint never kills the loop
                log.exception("before_tick failed at t=%.3f s", self.plant.time_s)
        t_read = time.perf_counter()
        sensors = self.plant.read()
        est = Estimate.for_tick()
        ctx = TickContext(tick=self.tick_count, time_s=sensors.time_s, dt_s=self.dt_control_s,
                          sensors=sensors, estimate=est, last_ports=self._ports, ports=Ports())
        ref_in = self._last_ref
        faulted = False
        try:
            ref = self.chain.tick(ctx, ref_in)
            q_cmd = np.asarray(ref.q_rad, dtype=float)
            if not np.isfinite(q_cmd).all():
                raise FloatingPointError("non-finite joint command")
        except Exception as exc:  # noqa: BLE001 - a fault ends in a safe stop, reported
            faulted = True
            self._on_fault(exc)
            ref = ref_in.with_(q_rad=self._last_q_cmd)
            q_cmd = self._last_q_cmd
            ctx.ports.hold = True  # hold's second writer (Ports): hes may not have run; safe_stop engaged it
        self._ports = ctx.ports
        fall = self.fall
        if fall is not None and fall.reason is None:
            if fall.check(est, self.dt_control_s) is not None:
                log.error("fall detected at t=%.3f s: %s", sensors.time_s, fall.reason)
                self.safe_stop("fallen", q_cmd)
        self.plant.write(q_cmd)
        t_written = time.perf_counter()
        self.read_to_write_timer.add((t_written - t_read) * 1e3)
        self._last_q_cmd = frozen_array(q_cmd)  # read-only (a copy unless already immutable): the snapshot shares it
        self._last_ref = ref
        t_after = time.perf_counter()
        if not faulted:  # a faulted tick's layers are suspect: nothing is prepared from it
            self._after_write()
        self.after_write_timer.add((time.perf_counter() - t_after) * 1e3)
        t_phys = time.perf_counter()
        try:
            self.plant.step(self.substeps)
        except Exception as exc:  # noqa: BLE001 - a physics blow-up is a fault too: safe stop, reported
            self._on_fault(exc)
        self.physics_timer.add((time.perf_counter() - t_phys) * 1e3)
        self.tick_count += 1
        loop_ms = (time.perf_counter() - t_start) * 1e3
        self.tick_timer.add(loop_ms)
        self.snapshot = self._make_snapshot(sensors, est, ref, loop_ms)
        if self._on_snapshot is not None:
            self._on_snapshot(self.snapshot)
        return self.snapshot

    def _after_write(self) -> None:
        """The layers' after-write work (Layer.after_write): the command is out, the next tick will read its
        result. An exception there is a fault as one in the chain: safe stop, and the next tick's layers hold."""
        try:
            self.chain.after_write(self._ports)
        except Exception as exc:  # noqa: BLE001 - a fault ends in a safe stop, reported
            self._on_fault(exc)
            self._ports.hold = True  # as after a faulted tick: the layers before hes hold from the next tick on

    def _on_fault(self, exc: BaseException) -> None:
        msg = f"{type(exc).__name__}: {exc}"
        if self.fault != msg:
            log.error("controller fault at t=%.3f s: %s\n%s", self.plant.read().time_s, msg,
                      traceback.format_exc())
        self.fault = msg
        self.safe_stop("fault", self._last_q_cmd)

    def safe_stop(self, reason: str, q_rad: np.ndarray | None = None) -> None:
        """Engage the chain's safe stop (its layer that declares `safe_stop`, the HardEmergencyStopper) for
        `reason`: "operator", "fault" or "fallen"."""
        layer = self.chain.safe_stop_layer
        if layer is not None:
            layer.engage(q_rad, reason=reason)

    @property
    def hard_stop_engaged(self) -> bool:
        return bool(getattr(self.chain.safe_stop_layer, "engaged", False))

    def clear_fault(self) -> None:
        self.fault = None

    def _make_snapshot(self, sensors: Sensors, est: Estimate, ref: Reference, loop_ms: float,
                       planned_q_rad: np.ndarray | None = None) -> Snapshot:
        if est.cog_world is not None:  # estimated by a layer this tick (the Stabilizer)
            cog, zmp = est.cog_world, est.zmp_world
        elif self._state_estimator is not None:  # no layer did: the same estimator, once
            cog, zmp = self._state_estimator(sensors, est, ref)
        else:
            cog, zmp = np.zeros(3), np.zeros(3)
        timers = self.chain.timers
        layers = {name: layer.status() for name, layer in self.chain.layers.items()}
        stop = self.chain.safe_stop_layer
        safety = Safety(hard_stop=bool(getattr(stop, "engaged", False)), hard_stop_reason=getattr(stop, "reason", None),
                        fault=self.fault, fall=None if self.fall is None else self.fall.reason,
                        hard_stop_stopping=getattr(stop, "stopping", None))
        planned = self._ports.planned_q_rad if planned_q_rad is None else planned_q_rad
        return Snapshot(
            tick=self.tick_count, time_s=float(sensors.time_s if self.tick_count == 0 else self.plant.time_s),
            q_cmd_rad=frozen_array(self._last_q_cmd), q_seq_rad=frozen_array(ref.q_rad if planned is None else planned),
            q_meas_rad=sensors.q_rad, reference=ref,
            base_rpy_est_rad=frozen_array(est.base_rpy_rad), wrenches_ext=frozen_array(est.wrenches_ext),
            cog_world=frozen_array(cog), zmp_world=frozen_array(zmp), layers=layers,
            layer_tick_ms={name: t.last_ms for name, t in timers.items()},
            safety=safety, loop_ms=loop_ms, odometry=est.odometry,
        )

    # ---- synchronous running ----------------------------------------------------------------
    def run_for(self, seconds: float) -> Snapshot:
        n = int(round(seconds / self.dt_control_s))
        snap = self.snapshot
        for _ in range(n):
            snap = self.step()
        return snap

    def run_until(self, predicate: Callable[[Snapshot], bool], timeout_s: float) -> Snapshot:
        """Step until `predicate(snapshot)` holds; raise TimeoutError after `timeout_s` of sim time."""
        n = int(round(timeout_s / self.dt_control_s))
        for _ in range(n):
            snap = self.step()
            if predicate(snap):
                return snap
        raise TimeoutError(f"condition not reached within {timeout_s} s of simulated time")

    # ---- paced running -------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        """A background thread ticks (start())."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def pacing(self) -> bool:
        """run_paced is ticking, in a background thread or in the caller's (the robot process's main thread):
        nothing may wait at a tick boundary for work done elsewhere."""
        return self._pacing

    def start(self, speed: float | None = 1.0) -> None:
        """Run in a background thread; `speed` 1.0 = real time, None = as fast as possible."""
        if speed is not None and not speed > 0:
            raise InvalidCommand(f"speed must be > 0 or None (as fast as possible), got {speed}")
        if self.running:
            return
        self.speed = speed
        self._stop_event.clear()
        self._thread = threading.Thread(target=self.run_paced, name="control-loop", daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        self._stop_event.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        self._thread = None
        self._drain()

    def request_stop(self) -> None:
        """Make run_paced return after the current boundary (from inside the loop, or from another thread)."""
        self._stop_event.set()

    def timing(self) -> LoopTiming:
        """Tick start-lateness and simulated / wall time of the paced run so far."""
        return self.lateness.summary()

    def run_paced(self, wait: Callable[[float], None] | None = None,
                  between_ticks: Callable[[], None] | None = None) -> None:
        """Tick until stop(): paced to wall time at `self.speed` (None: as fast as possible).

        `wait(seconds)` sleeps until the next tick is due (default: an interruptible sleep), in naps of
        `nap_s` if set; an owner may wait on its command channels instead and handle what arrives, since
        nothing ticks meanwhile.
        `between_ticks()` runs at every tick boundary before the tick (commands, e-stop, publishing).
        The lateness of each tick's start against its schedule is measured (`timing()`)."""
        self._pacing = True
        try:
            self._run_paced(wait, between_ticks)
        finally:
            self._pacing = False

    def _run_paced(self, wait: Callable[[float], None] | None, between_ticks: Callable[[], None] | None) -> None:
        sleep = wait or self._stop_event.wait
        clock = time.perf_counter
        meter = self.lateness
        meter.clear()
        wall0, sim0 = clock(), self.snapshot.time_s
        anchored_speed, anchored_resets = self.speed, self.resets
        meter.speed_target = self.speed
        while not self._stop_event.is_set():
            speed = self.speed
            t_sim = self.snapshot.time_s
            if speed != anchored_speed or self.resets != anchored_resets:  # a new speed, or a reset: a new schedule
                wall0, sim0, anchored_speed, anchored_resets = clock(), t_sim, speed, self.resets
                meter.clear()
                meter.speed_target = speed
            if speed is not None:
                due = self.due_s = wall0 + (t_sim - sim0) / speed
                delay = due - clock()
                while delay > 0 and not self._stop_event.is_set() and self.resets == anchored_resets:
                    sleep(min(delay, self.nap_s) if self.nap_s > 0.0 else delay)
                    delay = due - clock()
                if self._stop_event.is_set():
                    break
                if self.resets != anchored_resets:
                    continue  # reset while waiting: start the new schedule
                lateness = -delay
                if lateness > 0.25:  # far behind (debugger, suspended machine): re-anchor instead of racing
                    wall0, sim0 = clock(), t_sim
            else:
                lateness = 0.0
            if between_ticks is not None:
                between_ticks()
                if self.resets != anchored_resets:
                    continue  # a reset at this boundary: not a tick of the old schedule
            meter.add(lateness, clock(), t_sim)
            try:
                self.step()
            except Exception as exc:  # noqa: BLE001 - the plant itself failed: report, hold, go on
                self._on_fault(exc)
                self._stop_event.wait(self.dt_control_s)
