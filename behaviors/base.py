"""The shape of a behaviour ([OP] IV, the behaviour level): an interruptible state that produces twists for
operational points each tick and discrete commands through `Commands`, never reaching into a layer.

Life of a run (driven by behaviors.runner.BehaviorRunner, at tick boundaries inside the control loop):
`start(ctx)` once, then `step(ctx) -> Output` every tick until the behaviour calls `succeed` or `fail`,
or until it is interrupted (cancel, overrun, an exception), in which case `stop(ctx)` runs; `teardown(ctx)`
runs at the end in every case. A behaviour reads the robot only through `ctx.view` (the operation layer's
OperationView, the controller's own reference and odometry) and `ctx.commands` (the controller's encoders
and commands, never the simulator's ground truth).
"""

from __future__ import annotations

import dataclasses
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

import numpy as np

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.layer import Params
from controller.core.types import OdometryEstimate, WalkCommand
from controller.operation.points import OperationView, Twist

OVERRUN_FACTOR = 1.5  # a behaviour (a run, a plan's step) fails when it has taken this many times its nominal duration

__all__ = ["Behavior", "BehaviorParams", "Capture", "Commands", "Context", "JointReading", "Output", "params_from"]


@dataclass(frozen=True)
class BehaviorParams(Params):
    """Base of a behaviour's frozen parameter dataclass: every field with a default and, in its metadata,
    a unit, a range (`min`, `max`), `choices` and a `doc` (the HTTP API's schema is generated from them)."""


@dataclass(frozen=True, slots=True)
class JointReading:
    """One joint as the controller sees it: its command, its encoder, its limits [rad]."""

    q_cmd_rad: float
    q_meas_rad: float
    lower_rad: float
    upper_rad: float


@dataclass(frozen=True, slots=True)
class Capture:
    """One camera image requested at a tick boundary, and what the robot knew of itself at that instant.

    `frames` is rendered off the control thread; its result, indexed by the camera name, is the image (RGB,
    depth, intrinsics; no pose). The snapshot's encoders, KalmanFilter attitude and estimated COG are the
    inputs of the robot's own head-pose estimate (behaviors.perception.head_pose)."""

    camera: str
    frames: Future  # -> robot.images.Frames (frames.result()[camera] is the CameraImage), or the analysis' result
    time_s: float  # control time of the state the image shows [s]
    q_meas_rad: np.ndarray  # (30,) encoders
    base_rpy_est_rad: np.ndarray  # (3,) KalmanFilter attitude
    odometry: OdometryEstimate  # leg odometry: the stance sole and the controller's frame in the world
    ready: Callable[[], bool]  # whether `frames`' result enters at this boundary (ask from its due time on):
    #     as fast as possible it is waited for when due, so a seeded run is the same every time; paced, only
    #     once it is done, so no tick waits for the camera (RobotHost.capture_ready)


class Commands(Protocol):
    """The controller's command interface for behaviours. The host implements it by applying the operator
    service's own verbs, so a behaviour meets the same refusals as the operator (e-stop, motion stop, a
    fall): a refused command raises, and the run fails with that message."""

    def go_pos(self, x_m: float, y_m: float, theta_rad: float) -> float:
        """hrpsys goPos relative to the current feet frame F; returns the planned walk's duration [s]."""
        ...

    def walk_stop(self) -> None:
        """goStop: stop after the committed steps, feet side by side."""
        ...

    def walk_plan_version(self) -> int:
        """Changes whenever the AutoBalancer's footstep list is replaced or edited (another goPos, goVelocity or
        footstep list, a catching step, a walking stop): whether a walk went as it was planned."""
        ...

    def close_stance(self) -> float:
        """One slow, lowered step closing a stance too wide to walk from; returns its duration [s]."""
        ...

    def set_joint_angles(self, angles_rad: Mapping[str, float], time_s: float) -> None:
        """Interpolate the named joints (SequencePlayer) to `angles_rad` in `time_s` [s]."""
        ...

    def is_interpolating(self) -> bool:
        """Whether the SequencePlayer still interpolates."""
        ...

    def reset_operation_targets(self) -> float:
        """The operation layer's targets back onto the current reference (nothing offset any more); returns how
        long its output takes to blend there [s]."""
        ...

    def joint(self, name: str) -> JointReading:
        """The command, encoder and limits of one joint, as of the last tick."""
        ...

    def wrench(self, sensor: str) -> np.ndarray:
        """(6,) force [N] and moment [N m] of a force sensor ("rhsensor", ...) in its frame, offsets and the
        weight of the parts below it removed (RemoveForceOffset), as of the last tick."""
        ...

    def capture(self, camera: str, analyse: tuple | None = None) -> Capture:
        """Render `camera` from the state of this tick boundary, off the control thread. `analyse` = (fn, args):
        the capture's `frames` is then fn(frames, camera, time_s, q_meas_rad, base_rpy_est_rad, odometry,
        *args), computed where the image is rendered (fn a module-level function)."""
        ...

    def remember(self, object_name: str, recognition: Mapping[str, Any]) -> None:
        """Keep the latest recognition of an object (published for the console; later behaviours use it)."""
        ...

    def recalled(self, object_name: str) -> Mapping[str, Any] | None:
        """The latest recognition of an object remembered since the last reset, or None."""
        ...

    def plan_go_pos(self, x_m: float, y_m: float, theta_rad: float, soles: tuple | None = None) -> list:
        """The footsteps (behaviors.preview.PlannedStep, world) a goPos of (x, y, theta) relative to the feet
        frame would walk, from the AutoBalancer's own footstep planner, without walking: from the feet where
        they stand, or from `soles` (right, left PlannedStep, world) where a planned walk leaves them."""
        ...


@dataclass(frozen=True, slots=True)
class Context:
    """What a behaviour sees at one tick boundary."""

    time_s: float  # control time of the tick about to run [s]
    elapsed_s: float  # since the run started [s]
    dt_s: float  # control period [s]
    view: OperationView | None  # None when the chain has no operation layer
    commands: Commands

    def require_view(self) -> OperationView:
        if self.view is None:
            raise InvalidState("this behaviour needs the operation layer's view ('op'): the layer is not in the "
                               "chain, or has not ticked yet")
        return self.view


@dataclass(frozen=True, slots=True)
class Output:
    """What a behaviour asks for this tick: twists per operational point (feet frame F, see
    controller.operation.points) and, for the walking point, the walk command."""

    twists: Mapping[str, Twist] = field(default_factory=dict)
    walk: WalkCommand | None = None


NOTHING = Output()


class Behavior(ABC):
    """One behaviour per subclass, one subclass per file. Subclasses set `name`, `Params` and `summary`."""

    name: ClassVar[str]
    Params: ClassVar[type[BehaviorParams]]
    summary: ClassVar[str] = ""

    def __init__(self, params: BehaviorParams | None = None) -> None:
        params = self.Params() if params is None else params
        if not isinstance(params, self.Params):
            raise InvalidCommand(f"{self.name}: parameters must be {self.Params.__name__}, got {type(params).__name__}")
        self.params = params
        self.outcome: tuple[bool, str] | None = None  # (succeeded, message) once finished by itself
        self.result: dict[str, Any] = {}
        self.message = ""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.params!r})"

    # ---- what the runner asks -----------------------------------------------------------------------------
    def points(self) -> tuple[str, ...]:
        """The operational points this behaviour drives with twists."""
        return ()

    def resources(self) -> tuple[str, ...]:
        """What it needs alone: its points, and anything else it commands ("rhand.gripper"); two runs may
        not share one."""
        return self.points()

    @abstractmethod
    def nominal_duration_s(self) -> float:
        """How long the behaviour should take [s]; the runner fails it at OVERRUN_FACTOR times this."""

    def progress(self, ctx: Context) -> float:
        """0..1; by default the elapsed time against the nominal duration."""
        return min(1.0, ctx.elapsed_s / max(self.nominal_duration_s(), 1e-9))

    # ---- the state --------------------------------------------------------------------------------------------
    def start(self, ctx: Context) -> None:  # noqa: B027 - optional hook
        """Once, at the tick boundary the run is accepted; an exception refuses the run."""

    @abstractmethod
    def step(self, ctx: Context) -> Output:
        """Every tick boundary while running: this tick's twists (and walk command)."""

    def stop(self, ctx: Context) -> None:  # noqa: B027 - optional hook
        """Interrupted (cancelled, overran, failed in step): leave nothing moving behind."""

    def teardown(self, ctx: Context) -> None:  # noqa: B027 - optional hook
        """At the end of every run, however it ended."""

    # ---- before the run: what it would do (behaviors.preview) -------------------------------------------------
    def preview(self, ctx: Context, predicted: Any, into: Any, phase: str) -> Any:
        """Add the footsteps and hand paths this behaviour plans from `predicted` (behaviors.preview.Predicted,
        ctx.view is its view) to `into` (a MotionPreview) under `phase`; return the robot as it leaves it. By
        default it moves nothing a preview draws (a gaze, a gripper)."""
        return predicted

    def hold_between_phases(self) -> bool:
        """Run in step mode: wait before each phase until `allow_next_phase`. False: one phase only (the
        whole behaviour), nothing to hold."""
        return False

    def allow_next_phase(self) -> str:
        """Step mode: let the next phase start; returns its name."""
        return self.name

    # ---- helpers for subclasses ---------------------------------------------------------------------------------
    def succeed(self, message: str, **result: Any) -> Output:
        self.outcome = (True, message)
        self.message = message
        self.result.update(result)
        return NOTHING

    def fail(self, message: str, **result: Any) -> Output:
        self.outcome = (False, message)
        self.message = message
        self.result.update(result)
        return NOTHING


# ---- parameters from a request ---------------------------------------------------------------------------------
def held_by_collision(view: OperationView) -> str:
    """Why a goal check that reads the reference must not succeed while the CollisionDetector holds."""
    pairs = ", ".join(f"{a}-{b}" for a, b in view.collision_pairs)
    return (f"the CollisionDetector holds the last collision-free posture ({pairs} would collide): the robot "
            "did not follow the motion")


def params_from(cls: type[BehaviorParams], values: Mapping[str, Any], prefix: str = "") -> BehaviorParams:
    """`cls` built from plain values (JSON): unknown names, wrong types, non-finite numbers and values out of
    the declared range or choices raise InvalidCommand naming the field (after `prefix`) and what is allowed."""
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - set(fields))
    if unknown:
        raise InvalidCommand(f"{prefix}{unknown[0]}: unknown parameter of {cls.__name__}; valid: {sorted(fields)}")
    out: dict[str, Any] = {}
    for key, value in values.items():
        f = fields[key]
        kind = type(f.default)
        meta = f.metadata
        name = prefix + key
        if kind is float or kind is int:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InvalidCommand(f"{name}: must be a number (got {value!r})")
            if not math.isfinite(float(value)):
                raise InvalidCommand(f"{name}: must be a finite number (got {value!r})")
            if kind is int and not float(value).is_integer():
                raise InvalidCommand(f"{name}: must be an integer (got {value!r})")
            value = kind(value)
            lo, hi = meta.get("min"), meta.get("max")
            if (lo is not None and value < lo) or (hi is not None and value > hi):
                unit = meta.get("unit", "")
                raise InvalidCommand(f"{name}: {value:g} {unit} is outside the allowed range "
                                     f"[{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}]"
                                     f" {unit}")
        elif kind is bool:
            if not isinstance(value, bool):
                raise InvalidCommand(f"{name}: must be true or false (got {value!r})")
        elif kind is str:
            if not isinstance(value, str):
                raise InvalidCommand(f"{name}: must be a string (got {value!r})")
        elif kind is tuple:
            if not isinstance(value, (list, tuple)):
                raise InvalidCommand(f"{name}: must be a list (got {value!r})")
            value = tuple(value)
        choices = meta.get("choices")
        if choices is not None and value not in choices:
            raise InvalidCommand(f"{name}: {value!r} is not one of {list(choices)}")
        out[key] = value
    try:
        return cls(**out)
    except InvalidCommand as exc:
        raise InvalidCommand(f"{prefix.rstrip('.') or cls.__name__}: {exc}") from None


def describe(cls: type[Behavior]) -> dict[str, Any]:
    """A behaviour as the API lists it: name, summary, and each parameter's type, unit, range, default, doc."""
    types = {float: "number", int: "integer", bool: "boolean", str: "string", tuple: "array"}
    params = []
    for f in dataclasses.fields(cls.Params):
        entry = {"name": f.name, "type": types.get(type(f.default), "string"), "default": f.default}
        for key in ("unit", "min", "max", "choices", "doc", "place"):
            if f.metadata.get(key) is not None:
                entry[key] = list(f.metadata[key]) if key == "choices" else f.metadata[key]
        params.append(entry)
    return {"name": cls.name, "summary": cls.summary, "params": params}
