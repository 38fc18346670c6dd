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
from behaviors.preview import MotionPreview, Predicted, PreviewEnds

MAX_PREVIEW_STEPS = 100  # a preview follows a plan this many steps at most (a plan looping until a measurement)


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
        self.step_mode = False  # hold before each new phase until allow_next_phase (mc_rtc's step-by-step FSM)
        self.permits = 0  # phases allowed to start in step mode
        self.pending: Behavior | None = None  # the next phase's first child, held
        self.held_s = 0.0  # [s] spent held between phases (added to the nominal duration)
        self._started_phase: str | None = None

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
        return self.done_s + current + self.remaining_estimate_s + self.held_s

    # ---- step mode ----------------------------------------------------------------------------------------------
    def hold_between_phases(self) -> bool:
        self.step_mode = True
        self.permits = 1  # the step that starts the run runs the first phase
        return True

    def allow_next_phase(self) -> str:
        self.permits += 1
        return self.phase

    @property
    def waiting(self) -> bool:
        """Held between phases in step mode."""
        return self.pending is not None

    def _held(self, child: Behavior) -> bool:
        """Step mode: whether `child`, the first of a new phase, must wait for allow_next_phase."""
        if not self.step_mode or self.phase == self._started_phase:
            return False
        if self.permits <= 0:
            self.pending = child
            return True
        self.permits -= 1
        self._started_phase = self.phase
        return False

    # ---- preview: the plan followed on the robot as each step is planned to leave it ------------------------------
    def preview(self, ctx: Context, predicted: Predicted, into: MotionPreview, phase: str) -> Predicted:
        twin = type(self)(self.params)  # this behaviour's own plan, on a copy (nothing of this run changes)
        twin.ctx = ctx
        gen = twin.plan(ctx)
        finished: Behavior | None = None
        try:
            for _ in range(MAX_PREVIEW_STEPS):
                child = gen.send(finished) if finished is not None else next(gen)
                name = twin.phase or child.name
                if not isinstance(child, Wait) and (not into.phases or into.phases[-1]["phase"] != name):
                    into.phases.append({"phase": name, "behavior": child.name})
                predicted = child.preview(twin._child_ctx(twin.ctx), predicted, into, name)
                twin.ctx = Context(ctx.time_s, ctx.elapsed_s, ctx.dt_s, predicted.view, ctx.commands)
                child.outcome = (True, "previewed")
                finished = child
            else:
                into.ends = (f"the preview ends in phase {twin.phase!r}: the plan repeats its steps until what the "
                             "robot measures says it is done")
        except StopIteration:
            pass
        except StepFailed as exc:
            into.ends = f"the plan would fail: {exc}"
        except PreviewEnds as exc:
            into.ends = f"the preview ends in phase {twin.phase!r}: {exc}"
        except Exception as exc:  # noqa: BLE001 - the plan read what a step only knows once it has run
            into.ends = (f"the preview ends in phase {twin.phase!r}: the plan reads what its step measured "
                         f"({type(exc).__name__}: {exc})")
        finally:
            gen.close()
        return predicted

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
            if self._held(child):
                self.child = None
                return None
            started = self._start_child(ctx, child)
            if started is not None:
                return started
            if child.outcome is None:
                return None
            finished = child  # ended at its start: give it back at once

    def _start_child(self, ctx: Context, child: Behavior) -> Output | None:
        """Start the plan's next child; an Output (failed) when its start refused it."""
        self.child = child
        self.child_started_s = ctx.elapsed_s
        try:
            child.start(self._child_ctx(ctx))
        except Exception as exc:  # noqa: BLE001 - the step is refused: the behaviour fails, naming it
            self.child = None
            return self.fail(f"{self.phase or child.name}: {child.name} refused: {exc}")
        return None

    def step(self, ctx: Context) -> Output:
        self.ctx = ctx
        if self.pending is not None:
            if self.permits <= 0:
                self.held_s += ctx.dt_s
                return NOTHING
            child, self.pending = self.pending, None
            self.permits -= 1
            self._started_phase = self.phase
            started = self._start_child(ctx, child)
            if started is not None:
                return started
            if child.outcome is not None:  # ended at its start: give it back at once
                ended = self._advance(ctx, child)
                return NOTHING if ended is None else ended
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
