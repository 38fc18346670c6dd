"""The operator service's verbs: one frozen dataclass per operation, checked once where it is made
(console side), run inside the robot process at a tick boundary (`run(host)`).

A verb holds plain, picklable values in SI units (m, s, rad, N). `check(info)` validates what depends on
the robot (joint limits, body names, scenes); construction validates the rest. `run` may raise the
controller's InvalidState/InvalidCommand; the host turns those into the service's errors. Only this module
and the host index the chain by layer name. A verb sees the host as the `Host` protocol.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from app.service.errors import InvalidArgument, NotFound
from controller.core.errors import InvalidCommand
from controller.core.layer import Params
from controller.operation.ranges import WALK_MAX_ANGULAR_RAD_S, WALK_MAX_LINEAR_M_S
from controller.walking.footsteps import StepParams

if TYPE_CHECKING:
    from concurrent.futures import Future

    from app.service.stops import WalkingStopWatch
    from behaviors.runner import BehaviorRunner
    from controller.core.loop import ControlLoop
    from controller.system import ControllerSystem
    from robot.plant import MujocoPlant

MAX_MOTION_TIME_S = 3600.0  # [s] longest interpolation a verb asks for
MIN_MOTION_TIME_S = 0.005  # [s] one control period: the shortest interpolation that is not a jump
MAX_PUSH_FORCE_N = 2000.0  # [N]
MAX_PUSH_DURATION_S = 5.0  # [s]
MAX_GO_POS_M = 5.0  # [m] |x|, |y| of goPos
MAX_GO_POS_RAD = math.radians(360.0)  # |theta| of goPos
MAX_FOOTSTEPS = 50
MAX_FOOTSTEP_POS_M = 10.0  # [m] |pos| components of a setFootSteps entry
MAX_TARGET_POS_M = 5.0  # [m] |pos| components of a setTargetPose target
MAX_OBJECT_XY_M = 10.0  # [m] |x|, |y| where a scene object may be placed
MAX_OBJECT_Z_M = 3.0  # [m] highest body origin of a placed object (z >= 0)
TARGET_LIMBS = ("rarm", "larm", "rleg", "lleg")


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
    def release_estop(self, setpoints_before: int = 0) -> None: ...
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


def _finite(field_name: str, values: Sequence[float]) -> None:
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)):
            raise InvalidArgument(field_name, f"must contain numbers only (got {v!r})")
        if not math.isfinite(float(v)):
            raise InvalidArgument(field_name, f"must contain finite numbers only (got {v!r})")


def _bounded(field_name: str, value: float, lo: float, hi: float, unit: str, shown=lambda v: v) -> None:
    _finite(field_name, [value])
    if not lo <= value <= hi:
        raise InvalidArgument(field_name, f"{shown(value):g} {unit} is outside the allowed range "
                                          f"[{shown(lo):g}, {shown(hi):g}] {unit}")


def _motion_time(field_name: str, time_s: float) -> None:
    _bounded(field_name, time_s, MIN_MOTION_TIME_S, MAX_MOTION_TIME_S, "s")


def _deg(v: float) -> float:
    return math.degrees(v)


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


# ---- safety -------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ReleaseEstop(Verb):
    name = "release_estop"
    setpoints_before: int = 0  # the console's newest setpoint number when the release was sent

    def run(self, host: Host) -> str:
        host.release_estop(self.setpoints_before)
        return "hard e-stop released"


@dataclass(frozen=True)
class StopMotion(Verb):
    name = "stop_motion"

    def run(self, host: Host) -> str:
        host.layer("es").stop_motion()
        return "planned motion stopped"


@dataclass(frozen=True)
class ReleaseMotion(Verb):
    name = "release_motion"

    def run(self, host: Host) -> str:
        host.layer("es").release_motion()
        return "motion stop released"


# ---- walking (hrpsys AutoBalancerService) --------------------------------------------------------------
@dataclass(frozen=True)
class GoPos(Verb):
    """Walk to (x, y, theta) relative to the current feet's mid-coords; while walking (hrpsys), relative to
    the feet's mid-coords where the walk began, replacing the rest of the plan from the next free footstep."""

    name = "go_pos"
    motion = True
    x_m: float
    y_m: float
    theta_rad: float

    def __post_init__(self) -> None:
        _bounded("x", self.x_m, -MAX_GO_POS_M, MAX_GO_POS_M, "m")
        _bounded("y", self.y_m, -MAX_GO_POS_M, MAX_GO_POS_M, "m")
        _bounded("theta_deg", self.theta_rad, -MAX_GO_POS_RAD, MAX_GO_POS_RAD, "deg", _deg)

    def run(self, host: Host) -> str:
        abc = host.layer("abc")
        was_walking = abc.gait.walking
        n = abc.go_pos(self.x_m, self.y_m, self.theta_rad)
        goal = f"({self.x_m:g} m, {self.y_m:g} m, {math.degrees(self.theta_rad):g} deg)"
        if not was_walking:
            return f"walking to {goal} in {n} footsteps"
        if n == 0:
            return (f"re-planned: walking to {goal} relative to where this walk began, from where its last "
                    "step lands")
        return f"re-planned: walking to {goal} relative to where this walk began; {n} footsteps to go"


@dataclass(frozen=True)
class GoVelocity(Verb):
    name = "go_velocity"
    motion = True
    vx_m_s: float
    vy_m_s: float
    vtheta_rad_s: float

    def __post_init__(self) -> None:
        # the walking point's bounds (controller.operation.ranges): goVelocity walks the same way
        _bounded("vx", self.vx_m_s, -WALK_MAX_LINEAR_M_S, WALK_MAX_LINEAR_M_S, "m/s")
        _bounded("vy", self.vy_m_s, -WALK_MAX_LINEAR_M_S, WALK_MAX_LINEAR_M_S, "m/s")
        _bounded("vtheta_deg", self.vtheta_rad_s, -WALK_MAX_ANGULAR_RAD_S, WALK_MAX_ANGULAR_RAD_S, "deg/s", _deg)

    def run(self, host: Host) -> str:
        host.layer("abc").go_velocity(self.vx_m_s, self.vy_m_s, self.vtheta_rad_s)
        return (f"walking at ({self.vx_m_s:g} m/s, {self.vy_m_s:g} m/s, "
                f"{math.degrees(self.vtheta_rad_s):g} deg/s)")


@dataclass(frozen=True)
class WalkStop(Verb):
    """goStop: stop after the committed steps, feet side by side."""

    name = "walk_stop"

    def run(self, host: Host) -> str:
        host.layer("abc").go_stop()
        return "stopping"


@dataclass(frozen=True)
class WalkEmergencyStop(Verb):
    name = "walk_emergency_stop"

    def run(self, host: Host) -> str:
        host.walking_stop_watch.asked = True  # what raised the stop, for the refusals it causes
        host.layer("abc").emergency_stop_walking()
        return "walking emergency stop"


@dataclass(frozen=True)
class Footstep:
    leg: str  # "rleg" | "lleg"
    pos_m: tuple[float, float, float]
    rpy_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)


#: StepParams field -> (request name, unit shown, value shown from the SI value)
_STEP_FIELDS = {"step_height_m": ("step_height", "m", float), "step_time_s": ("step_time", "s", float),
                "toe_angle_rad": ("toe_angle_deg", "deg", math.degrees),
                "heel_angle_rad": ("heel_angle_deg", "deg", math.degrees)}


def step_params(changes: Mapping[str, float], prefix: str = "step.") -> StepParams:
    """StepParams from SI fields (step_height_m, step_time_s, toe_angle_rad, heel_angle_rad), each checked
    against StepParams' declared range and named as the request names it."""
    meta = {f.name: f.metadata for f in dataclasses.fields(StepParams)}
    for key, value in changes.items():
        request_name, unit, shown = _STEP_FIELDS[key]
        lo, hi = meta[key].get("min", -math.inf), meta[key].get("max", math.inf)
        _bounded(prefix + request_name, value, lo, hi, unit, shown)
    try:
        return StepParams(**changes)
    except InvalidCommand as exc:
        raise InvalidArgument(prefix.rstrip("."), str(exc)) from exc


@dataclass(frozen=True)
class SetFootsteps(Verb):
    """setFootSteps relative to the first footstep, which is snapped onto the current pose of its leg."""

    name = "set_footsteps"
    motion = True
    footsteps: tuple[Footstep, ...]
    step: StepParams | None = None  # for every footstep but the first

    def __post_init__(self) -> None:
        if not 1 <= len(self.footsteps) <= MAX_FOOTSTEPS:
            raise InvalidArgument("footsteps", f"give 1..{MAX_FOOTSTEPS} footsteps (got {len(self.footsteps)})")
        for i, f in enumerate(self.footsteps):
            if f.leg not in ("rleg", "lleg"):
                raise InvalidArgument(f"footsteps.{i}.leg", f"{f.leg!r} is not one of 'rleg', 'lleg'")
            for k, v in enumerate(f.pos_m):
                _bounded(f"footsteps.{i}.pos.{k}", v, -MAX_FOOTSTEP_POS_M, MAX_FOOTSTEP_POS_M, "m")
            for k, v in enumerate(f.rpy_rad):
                _bounded(f"footsteps.{i}.rpy_deg.{k}", v, -MAX_GO_POS_RAD, MAX_GO_POS_RAD, "deg", _deg)

    def run(self, host: Host) -> str:
        steps = [(f.leg, list(f.pos_m), list(f.rpy_rad)) for f in self.footsteps]
        per_step = None if self.step is None else [None] + [self.step] * (len(steps) - 1)
        n = host.layer("abc").set_footsteps(steps, per_step)
        return f"walking {n} footsteps"


@dataclass(frozen=True)
class GetFootsteps(Verb):
    name = "get_footsteps"
    recorded = False

    def run(self, host: Host) -> tuple[bool, tuple]:
        abc = host.layer("abc")
        return bool(abc.gait.walking), abc.remaining_footsteps()


# ---- the SequencePlayer (hrpsys SequencePlayerService) -------------------------------------------------
def _check_joint(info: RobotInfo, field_name: str, index: int, value_rad: float) -> None:
    lo, hi = info.joint_limits_rad(index)
    if not lo - 1e-9 <= value_rad <= hi + 1e-9:
        name = info.joint_names[index]
        raise InvalidArgument(field_name, f"{name}={math.degrees(value_rad):g} deg is outside the joint range "
                                          f"[{math.degrees(lo):.2f}, {math.degrees(hi):.2f}] deg")


@dataclass(frozen=True)
class SetJointAngles(Verb):
    """Interpolate to all 30 joint angles [rad] (JOINT_NAMES order) in `time_s`."""

    name = "set_joint_angles"
    motion = True
    sequence = True
    q_rad: tuple[float, ...]
    time_s: float

    def __post_init__(self) -> None:
        _finite("angles_deg", self.q_rad)
        _motion_time("time", self.time_s)

    def check(self, info: RobotInfo) -> None:
        if len(self.q_rad) != len(info.joint_names):
            raise InvalidArgument("angles_deg", f"a list must have exactly {len(info.joint_names)} values in "
                                                f"JOINT_NAMES order ({', '.join(info.joint_names)}); "
                                                f"got {len(self.q_rad)}")
        for i, v in enumerate(self.q_rad):
            _check_joint(info, f"angles_deg.{i}", i, v)

    def run(self, host: Host) -> str:
        host.layer("seq").set_joint_angles(np.array(self.q_rad), self.time_s)
        return f"interpolating over {self.time_s:g} s"


@dataclass(frozen=True)
class SetSomeJointAngles(Verb):
    """Interpolate some joints {name: angle [rad]} in `time_s`; the others keep their motion."""

    name = "set_some_joint_angles"
    motion = True
    sequence = True
    angles_rad: tuple[tuple[str, float], ...]
    time_s: float

    def __post_init__(self) -> None:
        if not self.angles_rad:
            raise InvalidArgument("angles_deg", "give at least one joint")
        for name, v in self.angles_rad:
            _finite(f"angles_deg.{name}", [v])
        _motion_time("time", self.time_s)

    def check(self, info: RobotInfo) -> None:
        unknown = [n for n, _ in self.angles_rad if n not in info.joint_names]
        if unknown:
            raise InvalidArgument("angles_deg", f"unknown joint name(s) {', '.join(map(repr, unknown))}; "
                                                f"valid joints: {', '.join(info.joint_names)}")
        for name, v in self.angles_rad:
            _check_joint(info, f"angles_deg.{name}", info.joint_names.index(name), v)

    def run(self, host: Host) -> str:
        seq = host.layer("seq")
        for name, v in self.angles_rad:  # one command at one tick boundary
            seq.set_joint_angle(name, float(v), self.time_s)
        return f"interpolating over {self.time_s:g} s"


@dataclass(frozen=True)
class SetTargetPose(Verb):
    """Move a limb's end effector to a pose (relative to `frame` if given) in `time_s`."""

    name = "set_target_pose"
    motion = True
    sequence = True
    limb: str
    pos_m: tuple[float, float, float]
    rpy_rad: tuple[float, float, float]
    time_s: float
    frame: str | None = None

    def __post_init__(self) -> None:
        if self.limb not in TARGET_LIMBS:
            raise InvalidArgument("limb", f"{self.limb!r} is not one of {', '.join(TARGET_LIMBS)}")
        for k, v in enumerate(self.pos_m):
            _bounded(f"pos.{k}", v, -MAX_TARGET_POS_M, MAX_TARGET_POS_M, "m")
        for k, v in enumerate(self.rpy_rad):
            _bounded(f"rpy_deg.{k}", v, -math.pi * 2, math.pi * 2, "deg", _deg)
        _motion_time("time", self.time_s)

    def run(self, host: Host) -> str:
        spec = self.limb if not self.frame else f"{self.limb}:{self.frame}"
        host.layer("seq").set_target_pose(spec, np.array(self.pos_m), np.array(self.rpy_rad), self.time_s)
        return f"{spec} moving over {self.time_s:g} s"


@dataclass(frozen=True)
class SetGroupSequence(Verb):
    """Interpolate a joint group through `goals_rad` (k, group size), each reached after its time."""

    name = "set_group_sequence"
    motion = True
    sequence = True
    group: str
    goals_rad: tuple[tuple[float, ...], ...]
    times_s: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.goals_rad) != len(self.times_s) or not self.goals_rad:
            raise InvalidArgument("times", "one time per goal, at least one goal")
        for g in self.goals_rad:
            _finite("goals", g)
        for t in self.times_s:
            _motion_time("times", t)

    def run(self, host: Host) -> str:
        host.layer("seq").set_joint_angles_sequence_of_group(self.group, np.array(self.goals_rad),
                                                             list(self.times_s))
        return f"{self.group}: {len(self.goals_rad)} goals over {sum(self.times_s):g} s"


@dataclass(frozen=True)
class SetJointAnglesSequence(Verb):
    """Interpolate all joints through `q_seq_rad` (k, 30), each reached after its time."""

    name = "set_joint_angles_sequence"
    motion = True
    sequence = True
    q_seq_rad: tuple[tuple[float, ...], ...]
    times_s: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.q_seq_rad) != len(self.times_s) or not self.q_seq_rad:
            raise InvalidArgument("times", "one time per posture, at least one posture")
        for q in self.q_seq_rad:
            _finite("postures", q)
        for t in self.times_s:
            _motion_time("times", t)

    def run(self, host: Host) -> str:
        host.layer("seq").set_joint_angles_sequence(np.array(self.q_seq_rad), list(self.times_s))
        return f"{len(self.q_seq_rad)} postures over {sum(self.times_s):g} s"


@dataclass(frozen=True)
class ClearSequence(Verb):
    name = "clear_sequence"

    def run(self, host: Host) -> str:
        host.layer("seq").clear()
        return "sequence cleared"


@dataclass(frozen=True)
class SequenceStatus(Verb):
    name = "sequence_status"
    recorded = False

    def run(self, host: Host) -> bool:
        return bool(host.layer("seq").is_interpolating())


# ---- layers: start / stop and parameters -------------------------------------------------------------------
#: layers that can be started and stopped, with the label messages use
STARTABLE = {"abc": "AutoBalancer", "st": "Stabilizer"}


@dataclass(frozen=True)
class StartLayer(Verb):
    name = "start_layer"
    motion = True
    layer: str

    def __post_init__(self) -> None:
        if self.layer not in STARTABLE:
            raise NotFound(f"no startable layer {self.layer!r}; startable: {', '.join(STARTABLE)}")

    def run(self, host: Host) -> str:
        host.layer(self.layer).start()
        return f"{STARTABLE[self.layer]} started"


@dataclass(frozen=True)
class StopLayer(Verb):
    name = "stop_layer"
    layer: str

    def __post_init__(self) -> None:
        if self.layer not in STARTABLE:
            raise NotFound(f"no startable layer {self.layer!r}; startable: {', '.join(STARTABLE)}")

    def run(self, host: Host) -> str:
        host.layer(self.layer).stop()
        return f"{STARTABLE[self.layer]} stopped"


@dataclass(frozen=True)
class StartImpedance(Verb):
    name = "start_impedance"
    motion = True
    limb: str

    def check(self, info: RobotInfo) -> None:
        _check_limb(info, self.limb)

    def run(self, host: Host) -> str:
        host.layer("ic").start(self.limb)
        return f"impedance control of {self.limb} started"


@dataclass(frozen=True)
class StopImpedance(Verb):
    name = "stop_impedance"
    limb: str

    def check(self, info: RobotInfo) -> None:
        _check_limb(info, self.limb)

    def run(self, host: Host) -> str:
        host.layer("ic").stop(self.limb)
        return f"impedance control of {self.limb} stopped"


def _check_limb(info: RobotInfo, limb: str) -> None:
    if limb not in info.impedance_limbs:
        raise NotFound(f"unknown limb {limb!r}; valid limbs: {', '.join(info.impedance_limbs)}")


def typed_changes(params: Params, changes: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """`changes` checked against the Params dataclass of `params`: known names, the field's type (no string
    or boolean for a number, no fraction for an integer), finite, inside the declared range and choices.
    Each rejection names the field (after `prefix`) and what is allowed."""
    cls = type(params)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    if not changes:
        raise InvalidArgument(prefix.rstrip(".") or "body", f"give at least one parameter; valid: {sorted(fields)}")
    unknown = sorted(set(changes) - set(fields))
    if unknown:
        raise InvalidArgument(prefix + unknown[0], f"unknown parameter(s) {unknown} of {cls.__name__}; "
                                                   f"valid: {sorted(fields)}")
    out: dict[str, Any] = {}
    for key, value in changes.items():
        name = prefix + key
        kind = type(getattr(params, key))
        meta = fields[key].metadata
        if kind is bool:
            if not isinstance(value, bool):
                raise InvalidArgument(name, f"must be true or false (got {value!r})")
        elif kind in (int, float):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InvalidArgument(name, f"must be a number (got {value!r})")
            try:
                as_float = float(value)
            except OverflowError:
                as_float = math.inf
            if not math.isfinite(as_float):
                raise InvalidArgument(name, f"must be a finite number (got {_short(value)})")
            if kind is int and not as_float.is_integer():
                raise InvalidArgument(name, f"must be an integer (got {value!r})")
            value = kind(value)
            lo, hi = meta.get("min"), meta.get("max")
            if (lo is not None and value < lo) or (hi is not None and value > hi):
                unit = meta.get("unit", "")
                raise InvalidArgument(name, f"{value:g} {unit} is outside the allowed range "
                                            f"[{'-inf' if lo is None else f'{lo:g}'}, "
                                            f"{'inf' if hi is None else f'{hi:g}'}] {unit} ({cls.__name__}.{key})")
        elif kind is str and not isinstance(value, str):
            raise InvalidArgument(name, f"must be a string (got {value!r})")
        choices = meta.get("choices")
        if choices is not None and value not in choices:
            raise InvalidArgument(name, f"{value!r} is not one of the allowed {list(choices)} ({cls.__name__}.{key})")
        out[key] = value
    try:
        params.replaced(**out)  # the dataclass's own invariants (cross-field checks)
    except InvalidCommand as exc:
        raise InvalidArgument(prefix.rstrip(".") or "body", str(exc)) from exc
    return out


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


@dataclass(frozen=True)
class SetParams(Verb):
    """Replace some parameters of one or more layers, all or none, at one tick boundary.

    `changes`: ((owner, ((field, value), ...)), ...) with owner a layer name or "ic:<limb>"."""

    name = "set_params"
    changes: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...]

    @staticmethod
    def of(info: RobotInfo, changes: Mapping[str, Mapping[str, Any]], prefixes: Mapping[str, str] | None = None
           ) -> SetParams:
        """Checked against the robot's parameter classes; `prefixes` name the fields in errors per owner."""
        out = []
        for owner, fields in changes.items():
            if owner not in info.params:
                raise NotFound(f"no parameters {owner!r}; valid: {', '.join(info.params)}")
            prefix = (prefixes or {}).get(owner, "")
            out.append((owner, tuple(typed_changes(info.params[owner], fields, prefix).items())))
        return SetParams(tuple(out))

    def run(self, host: Host) -> dict[str, Params]:
        new = {owner: host.params(owner).replaced(**dict(fields)) for owner, fields in self.changes}
        for owner, params in new.items():
            host.set_params(owner, params)
        return new


@dataclass(frozen=True)
class GetParams(Verb):
    name = "get_params"
    recorded = False
    owners: tuple[str, ...] = ()  # empty: all

    def run(self, host: Host) -> dict[str, Params]:
        return {o: host.params(o) for o in (self.owners or host.param_owners())}


@dataclass(frozen=True)
class EnableLayers(Verb):
    """Let layers work (True) or pass their input through (False): for benchmarks and diagnosis. The KalmanFilter,
    RemoveForceOffset and HardEmergencyStopper keep estimating and guarding when disabled (the bench says which ran)."""

    name = "enable_layers"
    enabled: tuple[tuple[str, bool], ...]

    def check(self, info: RobotInfo) -> None:
        unknown = [n for n, _ in self.enabled if n not in info.chain]
        if unknown:
            raise NotFound(f"no layer(s) {unknown}; the chain has {list(info.chain)}")

    def run(self, host: Host) -> str:
        for name, on in self.enabled:
            host.layer(name).enabled = bool(on)
        return ", ".join(f"{n} {'on' if on else 'off'}" for n, on in self.enabled)


# ---- the simulation ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Push(Verb):
    """Apply a world-frame force [N] at a body's COM for `duration_s` (a simulator operation)."""

    name = "push"
    body: str
    force_n: tuple[float, float, float]
    duration_s: float

    def __post_init__(self) -> None:
        _finite("force", self.force_n)
        magnitude = float(np.linalg.norm(self.force_n))
        if magnitude > MAX_PUSH_FORCE_N:
            raise InvalidArgument("force", f"magnitude {magnitude:.1f} N is above the allowed {MAX_PUSH_FORCE_N:g} N")
        _bounded("duration", self.duration_s, MIN_MOTION_TIME_S, MAX_PUSH_DURATION_S, "s")

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
        _finite("position", self.position_m)
        for axis, value in zip("xy", self.position_m[:2], strict=False):
            _bounded(f"position.{axis}", value, -MAX_OBJECT_XY_M, MAX_OBJECT_XY_M, "m")
        if len(self.position_m) == 3:
            _bounded("position.z", self.position_m[2], 0.0, MAX_OBJECT_Z_M, "m")
        _bounded("yaw", self.yaw_rad, -2 * math.pi, 2 * math.pi, "deg", math.degrees)

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
        _bounded("last_s", self.last_s, 0.005, 3600.0, "s")

    def run(self, host: Host):
        loop = host.loop
        ticks = max(1, int(round(self.last_s / loop.dt_control_s)))
        return loop.lateness.summary(last_ticks=ticks, last_windows=int(self.last_s))


# ---- sessions ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StartRecording(Verb):
    """Record a session to `path` (an MCAP file the robot process writes) from a fresh simulation: with
    `reset`, the simulation is reset first (same scene); without, the robot must be at its first tick."""

    name = "start_recording"
    recorded = False
    path: str
    reset: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.path, str) or not self.path.endswith(".mcap"):
            raise InvalidArgument("path", f"must be a path ending in .mcap (got {self.path!r})")

    def run(self, host: Host) -> dict:
        return host.start_recording(self.path, reset=self.reset)


@dataclass(frozen=True)
class StopRecording(Verb):
    """End the session being recorded; the result is its status once the file is finished."""

    name = "stop_recording"
    recorded = False

    def run(self, host: Host) -> dict:
        return host.stop_recording()


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


# ---- the operation layer and the behaviours ([OP] Eq. 5) ----------------------------------------------------
@dataclass(frozen=True)
class SetOperatorVelocity(Verb):
    """The operator's velocity for one operational point (through the command queue; the streamed path is
    app.service.setpoints), stamped with the control time of the boundary it is applied at."""

    name = "set_operator_velocity"
    motion = True
    setpoint: Any  # app.service.setpoints.Setpoint, checked where it was made

    def run(self, host: Host):
        return host.apply_setpoints({self.setpoint.point: self.setpoint})[0]


@dataclass(frozen=True)
class ResetOperationTargets(Verb):
    """The operation layer's targets back onto the current reference (nothing offset any more)."""

    name = "reset_operation_targets"
    motion = True

    def run(self, host: Host) -> str:
        host.layer("op").reset_targets()
        return "operation targets back on the reference"


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

    def __post_init__(self) -> None:
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
        return host.runner.run(self.build(), host.loop.plant.time_s)


@dataclass(frozen=True)
class CancelRun(Verb):
    name = "cancel_run"
    run_id: int

    def run(self, host: Host):
        return host.runner.cancel(self.run_id)


@dataclass(frozen=True)
class GetRun(Verb):
    name = "get_run"
    recorded = False
    run_id: int

    def run(self, host: Host):
        return host.runner.get(self.run_id)


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
                _bounded(f"position_m.{axis}", v, -MAX_POSITION_M, MAX_POSITION_M, "m")

    def run(self, host: Host) -> dict:
        return host.confirm_recognition(self.object_name, self.position_m)
