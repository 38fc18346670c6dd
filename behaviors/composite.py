"""Behaviours made of behaviours decided on the way (locate, then walk where the can turned out to be, ...):
a plan written as a generator that yields the next child behaviour and gets it back when it has ended."""

# A subclass writes `plan(ctx)`: `child = yield SomeBehavior(params)` runs that behaviour to its end (its start,
# its steps with the twists passed through, its teardown) and gives it back; `self.require(child)` raises
# StepFailed when it failed, which fails the whole behaviour naming the step. `yield Wait(seconds)` holds.
# The plan's return value is the success message. A cancel interrupts the running child (its `stop`). The
# composite claims up front every point its children may drive, so nothing else takes them meanwhile; the
# operator's own motion at those points still adds (Eq. 5).

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass, field
from typing import Any

from behaviors.base import NOTHING, OVERRUN_FACTOR, Behavior, BehaviorParams, Context, Output


class StepFailed(Exception):
    """A child behaviour of a plan failed; the message says which and why."""


@dataclass(frozen=True)
class WaitParams(BehaviorParams):
    time_s: float = field(default=0.5, metadata={"unit": "s", "min": 0.0, "max": 60.0})


class Wait(Behavior):
    """Hold for a time (a head settling before an image, ...); not listed as a behaviour of its own."""

    name = "wait"
    Params = WaitParams

    def __init__(self, time_s: float) -> None:
        super().__init__(WaitParams(time_s))

    def nominal_duration_s(self) -> float:
        return self.params.time_s + 0.1

    def step(self, ctx: Context) -> Output:
        if ctx.elapsed_s >= self.params.time_s - 1e-9:
            return self.succeed("waited")
        return NOTHING


Plan = Generator[Behavior, Behavior, str]


class Composite(Behavior):
    """Base of a behaviour whose children come from `plan`; `phases` (names) say what progress counts."""

    phases: tuple[str, ...] = ()
    #: [s] allowed for the steps not planned yet (the runner fails a run at 1.5 x its nominal duration)
    remaining_estimate_s: float = 30.0

    def __init__(self, params: BehaviorParams | None = None) -> None:
        super().__init__(params)
        self.child: Behavior | None = None
        self.child_started_s = 0.0
        self.done_s = 0.0  # [s] taken by the children that have ended
        self.phase = ""
        self.steps_log: list[dict[str, Any]] = []

    # ---- to write in subclasses ----------------------------------------------------------------------------------
    def plan(self, ctx: Context) -> Plan:  # pragma: no cover - abstract generator
        raise NotImplementedError
        yield

    def require(self, child: Behavior) -> Behavior:
        ok, message = child.outcome or (False, "did not end")
        if not ok:
            raise StepFailed(f"{self.phase or child.name}: {child.name} failed: {message}")
        return child

    def set_phase(self, phase: str) -> None:
        self.phase = phase
        self.result["phase"] = phase

    # ---- the Behavior interface --------------------------------------------------------------------------------
    def nominal_duration_s(self) -> float:
        current = self.child.nominal_duration_s() if self.child is not None else 0.0
        return self.done_s + current + self.remaining_estimate_s

    def progress(self, ctx: Context) -> float:
        if not self.phases:
            return super().progress(ctx)
        i = self.phases.index(self.phase) if self.phase in self.phases else 0
        within = self.child.progress(self._child_ctx(ctx)) if self.child is not None else 0.0
        return min(1.0, (i + within) / len(self.phases))

    @property
    def view(self):
        """The operation layer's view at the current tick boundary (for plans: `ctx` is the start's)."""
        return self.ctx.require_view()

    def start(self, ctx: Context) -> None:
        self.ctx = ctx
        self._gen = self.plan(ctx)
        self._advance(ctx, None)

    def _child_ctx(self, ctx: Context) -> Context:
        return Context(ctx.time_s, ctx.elapsed_s - self.child_started_s, ctx.dt_s, ctx.view, ctx.commands)

    def _advance(self, ctx: Context, finished: Behavior | None) -> Output | None:
        """Give the finished child back to the plan; start the next one. Returns an Output when the plan ended."""
        while True:
            try:
                child = self._gen.send(finished) if finished is not None else next(self._gen)
            except StopIteration as stop:
                self.child = None
                return self.succeed(str(stop.value or "done"))
            except StepFailed as exc:
                self.child = None
                return self.fail(str(exc))
            self.child = child
            self.child_started_s = ctx.elapsed_s
            try:
                child.start(self._child_ctx(ctx))
            except Exception as exc:  # noqa: BLE001 - the step is refused: the behaviour fails, naming it
                self.child = None
                return self.fail(f"{self.phase or child.name}: {child.name} refused: {exc}")
            if child.outcome is None:
                return None
            finished = child  # ended at its start: give it back at once

    def step(self, ctx: Context) -> Output:
        self.ctx = ctx
        child = self.child
        if child is None:
            return NOTHING
        child_ctx = self._child_ctx(ctx)
        out = child.step(child_ctx)
        if child.outcome is None:
            nominal = child.nominal_duration_s()
            if child_ctx.elapsed_s > OVERRUN_FACTOR * nominal:
                child.stop(child_ctx)
                child.teardown(child_ctx)
                self.child = None
                return self.fail(f"{self.phase or child.name}: {child.name} overran its nominal duration of "
                                 f"{nominal:.2f} s by 50 %")
            return out
        child.teardown(child_ctx)
        self.done_s += child_ctx.elapsed_s
        self.steps_log.append({"behavior": child.name, "ok": child.outcome[0], "message": child.outcome[1],
                               "duration_s": round(child_ctx.elapsed_s, 3)})
        self.result["steps"] = list(self.steps_log)
        ended = self._advance(ctx, child)
        return NOTHING if ended is None else ended

    def stop(self, ctx: Context) -> None:
        child = self.child
        if child is not None:
            child_ctx = self._child_ctx(ctx)
            child.stop(child_ctx)
            child.teardown(child_ctx)
            self.child = None
        self._gen.close()
