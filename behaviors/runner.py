"""Runs behaviours at the control loop's tick boundaries: ids, states, the 50 % overrun rule, one owner per
operational point, and the behaviours' sum per point handed to the operation layer ([OP] Eq. 5's
xi_behavior) for the next tick."""

from __future__ import annotations

import logging
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from behaviors.base import OVERRUN_FACTOR, Behavior, Commands, Context, Output
from behaviors.causes import run_cause
from behaviors.preview import MotionPreview, Predicted, PreviewCommands, PreviewEnds
from controller.core.errors import InvalidCommand, InvalidState, UnknownName
from controller.core.types import WalkCommand
from controller.operation.points import OperationView, Twist, check_twist, sum_per_point

log = logging.getLogger(__name__)

KEEP_FINISHED = 64  # finished runs kept for GET /api/behaviors/runs/{id}
STATES = ("running", "succeeded", "failed", "cancelled")
RUN_MODES = ("run", "step")  # without pauses; held before each phase until advance()


@dataclass(frozen=True)
class LatchedStop:
    """A stop of the controller no behaviour runs under: a run is refused while it is latched, and a running
    run it concerns ends, failed, with `message` as its cause."""

    reason: str  # what kind: "motion_stop" (EmergencyStopper), "walking_stop" (AutoBalancer)
    raised_by: str  # "operator", "capture_point", "emergency_step", "hard_stop"
    time_s: float | None  # simulated time it was raised [s]
    message: str  # what it is, what raised it and when, and what releases it
    points: tuple[str, ...] | None = None  # the runs it ends: those needing one of these (None: every run)

    def concerns(self, resources: Sequence[str]) -> bool:
        return self.points is None or any(p in resources for p in self.points)


class OperationPort(Protocol):
    """What the runner needs of the operation layer (controller.layers.operation.OperationLayer)."""

    def set_behavior(self, twists: Mapping[str, Twist], walk: WalkCommand | None = None) -> None: ...
    def view(self) -> OperationView: ...


@dataclass(frozen=True)
class RunStatus:
    """One run as the API shows it."""

    id: int
    behavior: str
    params: dict[str, Any]
    state: str  # running | succeeded | failed | cancelled
    progress: float  # 0..1
    message: str
    result: dict[str, Any]
    points: tuple[str, ...]  # what the run needs alone: operational points, "rhand.gripper", ...
    started_s: float  # control time [s]
    ended_s: float | None
    nominal_duration_s: float
    cause: str | None = None  # failed or cancelled: the cause its message names (behaviors.causes), else None
    mode: str = "run"  # run: without pauses; step: held before each phase until POST .../step
    waiting: bool = False  # step mode: held before its next phase

    def to_dict(self) -> dict[str, Any]:
        return {"id": self.id, "behavior": self.behavior, "params": self.params, "state": self.state,
                "progress": self.progress, "message": self.message, "result": self.result,
                "points": list(self.points), "started_s": self.started_s, "ended_s": self.ended_s,
                "nominal_duration_s": self.nominal_duration_s, "cause": self.cause,
                "mode": self.mode, "waiting": self.waiting}


@dataclass
class _Run:
    id: int
    behavior: Behavior
    started_s: float
    points: tuple[str, ...]
    resources: tuple[str, ...]
    state: str = "running"
    progress: float = 0.0
    message: str = "running"
    ended_s: float | None = None
    result: dict[str, Any] = field(default_factory=dict)
    drove_walk: bool = False  # it sent a walk command: on an interruption, one zero command follows
    mode: str = "run"

    def status(self) -> RunStatus:
        b = self.behavior
        return RunStatus(id=self.id, behavior=b.name, params=b.params.to_dict(), state=self.state,
                         progress=round(self.progress, 4), message=self.message, result=dict(self.result),
                         points=self.resources, started_s=self.started_s, ended_s=self.ended_s,
                         nominal_duration_s=b.nominal_duration_s(), mode=self.mode,
                         waiting=self.state == "running" and bool(getattr(b, "waiting", False)),
                         cause=run_cause(self.message) if self.state in ("failed", "cancelled") else None)


def _view(op: OperationPort | None, world_from_control: Callable[[], Sequence[float] | None] | None = None
          ) -> OperationView | None:
    """The op layer's view, or None (no layer, or none yet: before its first tick); placed in the world by
    `world_from_control()` (leg odometry: the controller's frame in the world) when that gives one."""
    if op is None:
        return None
    try:
        view = op.view()
    except (InvalidState, InvalidCommand):
        return None
    placement = None if world_from_control is None else world_from_control()
    return view if placement is None else view.placed_in_world(placement)


class BehaviorRunner:
    """Runs behaviours; `step(time_s)` is installed on ControlLoop.before_tick.

    `op()` returns the operation layer (None when the chain has none: behaviours that need a point are
    refused). Two runs may not drive the same point: the later one is refused, naming the running one."""

    def __init__(self, op: Callable[[], OperationPort | None], commands: Commands, dt_s: float,
                 world_from_control: Callable[[], Sequence[float] | None] | None = None,
                 stops: Callable[[], Sequence[LatchedStop]] | None = None) -> None:
        self._op = op
        #: the latched stops of the controller now (none: nothing in the way); checked when a run starts and
        #: at every tick boundary, so a run under a stop ends naming it instead of failing on its symptom
        self._stops = stops
        #: the controller's frame in the world (x, y, z, yaw), or None: the views the behaviours get are placed
        #: in the world with it, where perception and the map's places are
        self._world_from_control = world_from_control
        self.commands = commands
        self.dt_s = float(dt_s)
        self._next_id = 1
        self._running: OrderedDict[int, _Run] = OrderedDict()
        self._finished: OrderedDict[int, _Run] = OrderedDict()
        self._time_s = 0.0
        self._zero_walk = False  # an interrupted run was walking by velocity: send one zero walk command
        self.version = 0  # changes whenever a run starts, ends, or its progress is updated
        self.transitions = 0  # changes whenever a run starts or ends (not with its progress)

    def __repr__(self) -> str:
        return f"BehaviorRunner(running={[r.behavior.name for r in self._running.values()]})"

    # ---- commands (at a tick boundary) -------------------------------------------------------------------------
    def run(self, behavior: Behavior, time_s: float | None = None, mode: str = "run") -> int:
        """Start `behavior` now; returns its run id. Raises InvalidState when a running behaviour drives one
        of its points, InvalidCommand when the chain lacks what it needs, or what its start raised. `mode`
        "step": the run holds before each of its phases until `advance` (a behaviour of one phase just runs)."""
        if mode not in RUN_MODES:
            raise InvalidCommand(f"mode: {mode!r} is not one of {list(RUN_MODES)}")
        now = self._time_s if time_s is None else float(time_s)
        points = tuple(behavior.points())
        resources = tuple(dict.fromkeys((*points, *behavior.resources())))
        stops = self.latched()
        if stops:
            raise InvalidState(f"{behavior.name} refused: {stops[0].message}")
        op = self._op()
        if points and op is None:
            raise InvalidCommand(f"{behavior.name} drives {list(points)}, and the chain has no operation layer")
        for other in self._running.values():
            shared = sorted(set(resources) & set(other.resources))
            if shared:
                raise InvalidState(f"{behavior.name} refused: {shared} driven by run {other.id} "
                                   f"({other.behavior.name}); cancel it or wait until it ends")
        run = _Run(self._next_id, behavior, now, points, resources, mode=mode)
        if mode == "step":
            behavior.hold_between_phases()
        behavior.start(self._context(run, now, self._placed_view(op)))  # may raise: the run is refused
        self._next_id += 1
        self._running[run.id] = run
        self.version += 1
        self.transitions += 1
        return run.id

    @property
    def next_id(self) -> int:
        """The id the next run will get."""
        return self._next_id

    def continue_ids_from(self, next_id: int) -> None:
        """Number the next runs from `next_id` on (a replay of a session that began after a reset, when the
        runs before it had taken the ids below)."""
        if self._running or self._finished:
            raise InvalidState("run ids can only be set before the first run")
        self._next_id = int(next_id)

    def advance(self, run_id: int) -> RunStatus:
        """Step mode: let run `run_id` start its next phase (it then holds again before the one after)."""
        run = self._running.get(run_id)
        if run is None:
            if run_id in self._finished:
                raise InvalidState(f"run {run_id} has ended ({self._finished[run_id].state}): nothing to step")
            raise UnknownName(f"no run {run_id}; runs: {self.ids()}")
        if run.mode != "step":
            raise InvalidState(f"run {run_id} ({run.behavior.name}) runs without pauses (mode 'run'): nothing to "
                               "step; start it with mode 'step'")
        run.behavior.allow_next_phase()
        self.version += 1
        return run.status()

    def preview(self, behavior: Behavior) -> MotionPreview:
        """What `behavior` would do if it started now: its own plan followed on the robot as each step is planned
        to leave it (behaviors.preview); nothing is commanded."""
        view = self._placed_view(self._op())
        if view is None:
            raise InvalidCommand(f"{behavior.name}: a preview needs the operation layer's view ('op'): the layer "
                                 "is not in the chain, or has not ticked yet")
        ctx = Context(time_s=self._time_s, elapsed_s=0.0, dt_s=self.dt_s, view=view,
                      commands=PreviewCommands(self.commands))
        into = MotionPreview(behavior.name)
        if not hasattr(behavior, "plan"):
            into.phases.append({"phase": behavior.name, "behavior": behavior.name})
        try:
            behavior.preview(ctx, Predicted(view), into, behavior.name)
        except PreviewEnds as exc:
            into.ends = f"the preview ends: {exc}"
        return into

    def cancel(self, run_id: int) -> RunStatus:
        run = self._running.get(run_id)
        if run is None:
            if run_id in self._finished:
                return self._finished[run_id].status()  # already over: nothing to cancel (idempotent)
            raise UnknownName(f"no run {run_id}; runs: {self.ids()}")
        self._end(run, "cancelled", "cancelled by the operator", interrupted=True)
        return run.status()

    def cancel_all(self, message: str) -> None:
        for run in list(self._running.values()):
            self._end(run, "cancelled", message, interrupted=True)

    def reset(self, message: str) -> None:
        """The chain was rebuilt (a simulation reset): cancel every run; the zero walk command an interrupted
        velocity walk leaves is dropped, the walk it was for is gone with the old chain."""
        self.cancel_all(message)
        self._zero_walk = False

    def get(self, run_id: int) -> RunStatus:
        run = self._running.get(run_id) or self._finished.get(run_id)
        if run is None:
            raise UnknownName(f"no run {run_id}; runs: {self.ids()}")
        return run.status()

    def ids(self) -> list[int]:
        return sorted([*self._finished, *self._running])

    def runs(self) -> tuple[RunStatus, ...]:
        """Every run kept, oldest first (finished ones up to KEEP_FINISHED)."""
        return tuple(r.status() for r in sorted([*self._finished.values(), *self._running.values()],
                                                key=lambda r: r.id))

    @property
    def active(self) -> bool:
        return bool(self._running)

    def latched(self) -> tuple[LatchedStop, ...]:
        """The latched stops now, as the host tells them."""
        return () if self._stops is None else tuple(self._stops())

    def _end_stopped_runs(self) -> None:
        """Each run a latched stop concerns ends, failed, naming the stop (not the symptom its behaviour would
        meet: a gaze ending off target, a hand held short of its goal)."""
        stops = self.latched()
        if not stops:
            return
        for run in list(self._running.values()):
            stop = next((s for s in stops if s.concerns(run.resources)), None)
            if stop is not None:
                self._end(run, "failed", f"{run.behavior.name} stopped at t = {self._time_s:.3f} s: {stop.message}",
                          interrupted=True)

    # ---- every tick boundary -------------------------------------------------------------------------------------
    def step(self, time_s: float) -> None:
        """Step the running behaviours; hand their sum per point (and the walk command) to the op layer."""
        self._time_s = float(time_s)
        if self._running:
            self._end_stopped_runs()
        if not self._running and not self._zero_walk:
            return
        op = self._op()
        view = self._placed_view(op)  # once for every run: the op layer's FK costs ~0.2 ms
        outputs: list[Mapping[str, Twist]] = []
        walk: WalkCommand | None = None
        for run in list(self._running.values()):
            ctx = self._context(run, time_s, view)
            try:
                out = run.behavior.step(ctx)
                if not isinstance(out, Output):
                    raise TypeError(f"step returned {type(out).__name__}, not Output")
                run.progress = max(0.0, min(1.0, float(run.behavior.progress(ctx))))
                run.result = run.behavior.result  # live (a composite's phase, a recognition); copied by status()
                for point, twist in out.twists.items():
                    if point not in run.points:
                        raise InvalidCommand(f"{run.behavior.name} moved {point!r}, which it did not claim "
                                             f"({list(run.points)})")
                    check_twist(point, twist)
                if out.walk is not None and "walk" not in run.points:
                    raise InvalidCommand(f"{run.behavior.name} drove the walking point without claiming it")
            except Exception as exc:  # noqa: BLE001 - a behaviour never kills the loop
                log.warning("behaviour %s (run %d) failed: %s", run.behavior.name, run.id, exc)
                self._end(run, "failed", f"{type(exc).__name__}: {exc}", interrupted=True)
                continue
            if run.behavior.outcome is not None:
                ok, message = run.behavior.outcome
                if ok:
                    run.progress = 1.0
                self._end(run, "succeeded" if ok else "failed", message, interrupted=not ok)
                continue
            nominal = run.behavior.nominal_duration_s()
            if ctx.elapsed_s > OVERRUN_FACTOR * nominal:
                self._end(run, "failed", f"overran its nominal duration of {nominal:.2f} s by 50 % "
                                         f"({ctx.elapsed_s:.2f} s)", interrupted=True)
                continue
            outputs.append(out.twists)
            if out.walk is not None:
                walk = out.walk
                run.drove_walk = True
        if walk is None and self._zero_walk:
            walk = WalkCommand(0.0, 0.0, 0.0)
        self._zero_walk = False
        self.version += 1
        if op is not None and (outputs or walk is not None):
            op.set_behavior(sum_per_point(*outputs), walk)

    # ---- pieces ----------------------------------------------------------------------------------------------------
    def _placed_view(self, op: OperationPort | None) -> OperationView | None:
        return _view(op, self._world_from_control)

    def _context(self, run: _Run, time_s: float, view: OperationView | None) -> Context:
        return Context(time_s=float(time_s), elapsed_s=float(time_s) - run.started_s, dt_s=self.dt_s,
                       view=view, commands=self.commands)

    def _end(self, run: _Run, state: str, message: str, interrupted: bool) -> None:
        """Finish a run. Its twists are no longer summed from the next tick on (set_behavior holds for one
        tick only), so nothing it commanded keeps moving; an interrupted run's `stop` runs first."""
        ctx = self._context(run, self._time_s, self._placed_view(self._op()) if interrupted else None)
        if interrupted:
            try:
                run.behavior.stop(ctx)
            except Exception as exc:  # noqa: BLE001 - reported in the message
                message += f" (and its stop failed: {type(exc).__name__}: {exc})"
        try:
            run.behavior.teardown(ctx)
        except Exception as exc:  # noqa: BLE001
            message += f" (and its teardown failed: {type(exc).__name__}: {exc})"
        if interrupted and run.drove_walk:
            self._zero_walk = True
        run.state = state
        run.message = message
        run.result = dict(run.behavior.result)
        run.ended_s = self._time_s
        self._running.pop(run.id, None)
        self._finished[run.id] = run
        while len(self._finished) > KEEP_FINISHED:
            self._finished.popitem(last=False)
        self.transitions += 1
        self.version += 1
