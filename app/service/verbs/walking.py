"""Walking verbs (hrpsys AutoBalancerService): goPos, goVelocity, goStop, setFootSteps; closeStance."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

from app.service.errors import InvalidArgument
from app.service.verbs.base import Host, Verb, check_bounded
from controller.core.errors import InvalidCommand, InvalidState
from controller.operation.ranges import WALK_MAX_ANGULAR_RAD_S, WALK_MAX_LINEAR_M_S
from controller.walking.footsteps import StepParams

MAX_GO_POS_M = 5.0  # [m] |x|, |y| of goPos
MAX_GO_POS_RAD = math.radians(360.0)  # |theta| of goPos
MAX_FOOTSTEPS = 50
MAX_FOOTSTEP_POS_M = 10.0  # [m] |pos| components of a setFootSteps entry


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
        check_bounded("x", self.x_m, -MAX_GO_POS_M, MAX_GO_POS_M, "m")
        check_bounded("y", self.y_m, -MAX_GO_POS_M, MAX_GO_POS_M, "m")
        check_bounded("theta_deg", self.theta_rad, -MAX_GO_POS_RAD, MAX_GO_POS_RAD, "deg", math.degrees)

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
        check_bounded("vx", self.vx_m_s, -WALK_MAX_LINEAR_M_S, WALK_MAX_LINEAR_M_S, "m/s")
        check_bounded("vy", self.vy_m_s, -WALK_MAX_LINEAR_M_S, WALK_MAX_LINEAR_M_S, "m/s")
        check_bounded("vtheta_deg", self.vtheta_rad_s, -WALK_MAX_ANGULAR_RAD_S, WALK_MAX_ANGULAR_RAD_S, "deg/s",
                      math.degrees)

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
class CloseStance(Verb):
    """A stance wider than a walk starts from (a catching step's landing) closed by one slow, lowered step."""

    name = "close_stance"
    motion = True

    def run(self, host: Host) -> str:
        host.layer("abc").close_stance()
        return "closing the stance: one foot steps beside the other"


@dataclass(frozen=True)
class WalkEmergencyStop(Verb):
    name = "walk_emergency_stop"

    def run(self, host: Host) -> str:
        abc = host.layer("abc")
        # as a release with nothing latched: an ok would say a stop is in force (soak seed 10176)
        if not abc.gait.walking and not abc.estep.active:
            raise InvalidState("not walking: the emergency walking stop has nothing to stop")
        host.walking_stop_watch.asked = True  # what raised the stop, for the refusals it causes
        abc.emergency_stop_walking()
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
        check_bounded(prefix + request_name, value, lo, hi, unit, shown)
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
                check_bounded(f"footsteps.{i}.pos.{k}", v, -MAX_FOOTSTEP_POS_M, MAX_FOOTSTEP_POS_M, "m")
            for k, v in enumerate(f.rpy_rad):
                check_bounded(f"footsteps.{i}.rpy_deg.{k}", v, -MAX_GO_POS_RAD, MAX_GO_POS_RAD, "deg", math.degrees)

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
