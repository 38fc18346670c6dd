"""Verbs of the operation layer and the behaviours ([OP] Eq. 5), and the recognitions the operator
confirms ([OP] II)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from app.service.errors import InvalidArgument, NotFound
from app.service.verbs.base import Host, Verb, check_bounded
from controller.core.errors import InvalidCommand


@dataclass(frozen=True)
class SetOperatorVelocity(Verb):
    """The operator's velocity for one operational point (through the command queue; the streamed path is
    app.service.setpoints), stamped with the control time of the boundary it is applied at."""

    name = "set_operator_velocity"
    motion = True
    setpoint: Any  # app.service.setpoints.Setpoint; out of its ranges the operation layer acknowledges it "invalid"

    def run(self, host: Host):
        return host.apply_setpoints({self.setpoint.point: self.setpoint})[0]


@dataclass(frozen=True)
class ResetOperationTargets(Verb):
    """The operation layer's targets back onto the current reference (nothing offset any more)."""

    name = "reset_operation_targets"
    motion = True

    def run(self, host: Host) -> str:
        return f"operation targets back on the reference in {host.layer('op').reset_targets():.2f} s"


def _behavior_argument(exc: InvalidCommand) -> InvalidArgument:
    """An InvalidCommand from behaviors.registry ("field: message") as the service's field-named error."""
    field_name, sep, message = str(exc).partition(": ")
    return InvalidArgument(field_name if sep and " " not in field_name else "params", message if sep else str(exc))


@dataclass(frozen=True)
class RunBehavior(Verb):
    """Start a behaviour with parameters (plain JSON values); the result is its run id."""

    name = "run_behavior"
    motion = True
    behavior: str
    params: tuple[tuple[str, Any], ...] = ()
    mode: str = "run"  # "step": held before each phase until StepRun (behaviors.runner.RUN_MODES)

    def __post_init__(self) -> None:
        from behaviors.runner import RUN_MODES

        if self.mode not in RUN_MODES:
            raise InvalidArgument("mode", f"{self.mode!r} is not one of {list(RUN_MODES)}")
        self.build()  # checked where it is made: the field-named errors come back before anything is sent

    def build(self):
        from behaviors.registry import BEHAVIORS, make

        if self.behavior not in BEHAVIORS:
            raise NotFound(f"unknown behaviour {self.behavior!r}; valid: {', '.join(sorted(BEHAVIORS))}")
        try:
            return make(self.behavior, dict(self.params))
        except InvalidCommand as exc:
            raise _behavior_argument(exc) from None

    def run(self, host: Host) -> int:
        return host.runner.run(self.build(), host.loop.plant.time_s, self.mode)


@dataclass(frozen=True)
class PreviewBehavior(RunBehavior):
    """What a behaviour would do if it started now (behaviors.preview): its planned footsteps and hand paths
    from its own plan; nothing moves."""

    name = "preview_behavior"
    motion = False
    recorded = False

    def run(self, host: Host) -> dict:
        return host.runner.preview(self.build()).to_dict()


@dataclass(frozen=True)
class _OnRun(Verb):
    """A verb on one run: the runner's method `action` called with its id."""

    action: ClassVar[str]
    run_id: int

    def run(self, host: Host):
        return getattr(host.runner, self.action)(self.run_id)


@dataclass(frozen=True)
class StepRun(_OnRun):
    """Step mode: let a run start its next phase."""

    name = "step_run"
    motion = True
    action = "advance"


@dataclass(frozen=True)
class CancelRun(_OnRun):
    name = "cancel_run"
    action = "cancel"


@dataclass(frozen=True)
class GetRun(_OnRun):
    name = "get_run"
    recorded = False
    action = "get"


@dataclass(frozen=True)
class ListRuns(Verb):
    name = "list_runs"
    recorded = False

    def run(self, host: Host):
        return host.runner.runs()


@dataclass(frozen=True)
class ListBehaviors(Verb):
    """Every behaviour with its parameters' types, units and ranges (from each behaviour's Params class)."""

    name = "list_behaviors"
    recorded = False

    def run(self, host: Host) -> list[dict]:
        return list_behaviors()


def list_behaviors() -> list[dict]:
    from behaviors.base import describe
    from behaviors.registry import BEHAVIORS

    return [describe(cls) for _, cls in sorted(BEHAVIORS.items())]


# ---- the recognitions the operator confirms ([OP] II) -------------------------------------------
MAX_POSITION_M = 20.0  # [m] |component| of an operator's corrected object position (world)


@dataclass(frozen=True)
class ConfirmRecognition(Verb):
    """The operator confirms the latest recognition of an object, or corrects its position (world) [m]."""

    name = "confirm_recognition"
    object_name: str
    position_m: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        if self.position_m is not None:
            if len(self.position_m) != 3:
                raise InvalidArgument("position_m", f"give x, y, z [m] (got {len(self.position_m)} values)")
            for axis, v in zip("xyz", self.position_m, strict=True):
                check_bounded(f"position_m.{axis}", v, -MAX_POSITION_M, MAX_POSITION_M, "m")

    def run(self, host: Host) -> dict:
        return host.confirm_recognition(self.object_name, self.position_m)
