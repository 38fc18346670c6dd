"""`sequence`: run behaviours one after the other ("approach, reach, grasp, lift"); it fails at the first
step that fails, naming it, and a cancel interrupts the step that runs."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from behaviors.base import NOTHING, OVERRUN_FACTOR, Behavior, BehaviorParams, Context, Output
from behaviors.steps import STEPS, make_from
from controller.core.errors import InvalidCommand

MAX_STEPS = 20


@dataclass(frozen=True)
class SequenceParams(BehaviorParams):
    steps: tuple = field(default=(), metadata={"unit": "-", "doc": "the behaviours in order: "
                                               "[{\"behavior\": name, \"params\": {...}}, ...] (no nested sequence)"})

    def validate(self) -> None:
        super().validate()
        if not 1 <= len(self.steps) <= MAX_STEPS:
            raise InvalidCommand(f"steps: give 1..{MAX_STEPS} steps (got {len(self.steps)})")
        self.children()  # every step must build

    def children(self) -> list[Behavior]:
        out = []
        for i, step in enumerate(self.steps):
            if not isinstance(step, Mapping) or "behavior" not in step:
                raise InvalidCommand(f"steps.{i}: must be an object {{\"behavior\": name, \"params\": {{...}}}}")
            extra = sorted(set(step) - {"behavior", "params"})
            if extra:
                raise InvalidCommand(f"steps.{i}.{extra[0]}: unknown key; valid: ['behavior', 'params']")
            name = step["behavior"]
            if name == "sequence":
                raise InvalidCommand(f"steps.{i}.behavior: a sequence cannot contain a sequence")
            params = step.get("params") or {}
            if not isinstance(params, Mapping):
                raise InvalidCommand(f"steps.{i}.params: must be an object")
            out.append(make_from(STEPS, name, params, prefix=f"steps.{i}.params."))
        return out


class Sequence(Behavior):
    name = "sequence"
    Params = SequenceParams
    summary = "Run behaviours one after the other (steps: [{behavior, params}, ...])"

    def __init__(self, params: SequenceParams | None = None) -> None:
        super().__init__(params)
        self.steps = self.params.children()
        self.index = 0
        self.step_started_s = 0.0

    def points(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(p for b in self.steps for p in b.points()))

    def resources(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(r for b in self.steps for r in b.resources()))

    def nominal_duration_s(self) -> float:
        return sum(b.nominal_duration_s() for b in self.steps)

    def _child(self, ctx: Context) -> Context:
        return Context(ctx.time_s, ctx.elapsed_s - self.step_started_s, ctx.dt_s, ctx.view, ctx.commands)

    def progress(self, ctx: Context) -> float:
        if self.index >= len(self.steps):
            return 1.0
        return (self.index + self.steps[self.index].progress(self._child(ctx))) / len(self.steps)

    def start(self, ctx: Context) -> None:
        self.step_started_s = ctx.elapsed_s
        self.steps[0].start(self._child(ctx))

    def step(self, ctx: Context) -> Output:
        child = self.steps[self.index]
        child_ctx = self._child(ctx)
        out = child.step(child_ctx)
        if child.outcome is None:
            nominal = child.nominal_duration_s()
            if child_ctx.elapsed_s > OVERRUN_FACTOR * nominal:
                child.stop(child_ctx)
                child.teardown(child_ctx)
                return self.fail(f"step {self.index} ({child.name}) overran its nominal duration of "
                                 f"{nominal:.2f} s by 50 %", failed_step=self.index)
            return out
        ok, message = child.outcome
        child.teardown(child_ctx)
        self.result[f"{self.index}.{child.name}"] = {"message": message, **child.result}
        if not ok:
            return self.fail(f"step {self.index} ({child.name}) failed: {message}", failed_step=self.index)
        self.index += 1
        if self.index == len(self.steps):
            return self.succeed(f"all {len(self.steps)} steps done")
        self.step_started_s = ctx.elapsed_s
        try:
            self.steps[self.index].start(self._child(ctx))
        except Exception as exc:  # noqa: BLE001 - the step is refused: the sequence fails, naming it
            return self.fail(f"step {self.index} ({self.steps[self.index].name}) refused: {exc}",
                             failed_step=self.index)
        return NOTHING

    def stop(self, ctx: Context) -> None:
        if self.index < len(self.steps):
            child = self.steps[self.index]
            child_ctx = self._child(ctx)
            child.stop(child_ctx)
            child.teardown(child_ctx)

    def describe_steps(self) -> list[dict[str, Any]]:
        return [{"behavior": b.name, "params": b.params.to_dict()} for b in self.steps]
