"""The verbs' common ground: the `Host` protocol (what a verb's `run` reaches of the robot process), the
`RobotInfo` a verb is checked against, the argument checks the verbs share, and the `Verb` base class."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from app.service.errors import InvalidArgument
from controller.core.layer import Params

if TYPE_CHECKING:
    from concurrent.futures import Future

    from app.service.stops import WalkingStopWatch
    from behaviors.runner import BehaviorRunner
    from controller.core.loop import ControlLoop
    from controller.system import ControllerSystem
    from robot.plant import MujocoPlant

MAX_MOTION_TIME_S = 3600.0  # [s] longest interpolation a verb asks for
MIN_MOTION_TIME_S = 0.005  # [s] one control period: the shortest interpolation that is not a jump


# ---- what a verb reaches of the robot process ------------------------------------------------------
class Host(Protocol):
    """The robot process as a verb's `run` and a behaviour's commands (app.service.commands) see it: the
    app.service.host.RobotHost that applies them at a tick boundary."""

    scene: str
    plant: MujocoPlant
    system: ControllerSystem
    runner: BehaviorRunner
    walking_stop_watch: WalkingStopWatch
    stats: Any  # RunStats: summary() of the run so far
    recognitions: dict[str, dict]  # object -> its latest recognition (behaviours remember them)
    captures: int  # captures made since the last reset

    @property
    def loop(self) -> ControlLoop: ...
    def apply(self, verb: Verb) -> Any: ...
    def apply_setpoints(self, table: Mapping[str, Any], time_s: float | None = None) -> list: ...
    def layer(self, name: str) -> Any: ...
    def info(self) -> RobotInfo: ...
    def cached_info(self) -> RobotInfo: ...
    def release_estop(self, setpoints_before: int = 0, sent_monotonic_s: float | None = None) -> None: ...
    def param_owners(self) -> list[str]: ...
    def params(self, owner: str) -> Params: ...
    def set_params(self, owner: str, params: Params) -> None: ...
    def reset(self, scene: str | None = None) -> None: ...
    def inject_fault(self, kind: str, layer: str = "st") -> str: ...
    def stop_loop(self) -> None: ...
    def start_recording(self, path, reset: bool = False) -> dict: ...
    def stop_recording(self) -> dict: ...
    def confirm_recognition(self, object_name: str, position_m=None) -> dict: ...
    def cameras(self) -> Any: ...
    def capture_ready(self, number: int, result: Future) -> bool: ...


# ---- what the console knows of the robot ------------------------------------------------------------
@dataclass(frozen=True)
class RobotInfo:
    """What the robot process tells the console once (and again after a reset): enough to check verbs."""

    scene: str
    scenes: tuple[str, ...]
    bodies: tuple[str, ...]  # MuJoCo bodies a push may act on
    joint_names: tuple[str, ...]
    q_lower_rad: tuple[float, ...]
    q_upper_rad: tuple[float, ...]
    chain: tuple[str, ...]  # layer names in chain order
    params: Mapping[str, Params]  # current parameters per layer ("ic:rarm" for a hand's impedance)
    impedance_limbs: tuple[str, ...]
    dt_control_s: float
    speed: float | None
    objects: tuple[str, ...] = ()  # the scene's placeable objects (a simulator operation moves them)

    def joint_limits_rad(self, index: int) -> tuple[float, float]:
        return self.q_lower_rad[index], self.q_upper_rad[index]


def check_finite(field_name: str, values: Sequence[float]) -> None:
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)):
            raise InvalidArgument(field_name, f"must contain numbers only (got {v!r})")
        if not math.isfinite(float(v)):
            raise InvalidArgument(field_name, f"must contain finite numbers only (got {v!r})")


def check_bounded(field_name: str, value: float, lo: float, hi: float, unit: str, shown=lambda v: v) -> None:
    check_finite(field_name, [value])
    if not lo <= value <= hi:
        raise InvalidArgument(field_name, f"{shown(value):g} {unit} is outside the allowed range "
                                          f"[{shown(lo):g}, {shown(hi):g}] {unit}")


def check_motion_time(field_name: str, time_s: float) -> None:
    check_bounded(field_name, time_s, MIN_MOTION_TIME_S, MAX_MOTION_TIME_S, "s")


class Verb:
    """An operation of the operator service. `motion` verbs move the robot: they are refused while the
    hard e-stop is engaged or the robot has fallen; `sequence` verbs also while the CollisionDetector
    holds the posture or the EmergencyStopper holds the motion. `recorded` verbs are inputs of a session
    (a replay applies them again at the same tick); the others only read, or manage the recording."""

    name: ClassVar[str] = "verb"
    motion: ClassVar[bool] = False
    sequence: ClassVar[bool] = False
    recorded: ClassVar[bool] = True

    def check(self, info: RobotInfo) -> None:  # noqa: B027 - optional hook
        """Checks that need the robot's model (joint limits, names); raises InvalidArgument."""

    def run(self, host: Host) -> Any:
        raise NotImplementedError
