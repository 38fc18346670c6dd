"""Footstep planning as in hrpsys GaitGenerator: goPos, goVelocity / goStop / emergencyStop, setFootSteps."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.layer import Params
from controller.kinematics.rotations import matrix_to_rpy, rpy_to_matrix

__all__ = [
    "ANKLE_HEIGHT_M",
    "LEGS",
    "Footstep",
    "FootstepParams",
    "StepParams",
    "StrideLimits",
    "VelocityStepper",
    "capped_stride_limits",
    "clamp_stride",
    "go_pos",
    "go_pos_from",
    "mid_coords",
    "other_leg",
    "set_footsteps",
    "stop_in_place",
]

LEGS = ("rleg", "lleg")
ANKLE_HEIGHT_M = 0.105  # HRP-2 ankle joint above the sole frame [m]
_GO_POS_POS_TOL_M = 1e-4  # hrpsys goPos loop ends below 0.1 mm ...
_GO_POS_TH_TOL_RAD = math.radians(0.5)  # ... and 0.5 deg of remaining motion
_ALIGNED_TOL = 1e-9  # a foot closer than this to its goal pose needs no extra aligning step [m] / [rad]


def other_leg(leg: str) -> str:
    return "lleg" if leg == "rleg" else "rleg"


def _check_leg(leg: str) -> None:
    if leg not in LEGS:
        raise InvalidCommand(f"unknown leg {leg!r}; valid legs: {list(LEGS)}")


@dataclass(frozen=True, slots=True)
class Footstep:
    """Where one foot lands, and how it gets there.

    The pose is that of the sole frame (on the sole plane, under the ankle, x forward) in the world:
    position (x, y, z) [m] and fixed-axis roll-pitch-yaw [rad] (R = Rz(yaw) Ry(pitch) Rx(roll)).
    The step parameters describe the swing that ends on this footstep. The first footstep of a plan is
    the current support foot (step_height_m = 0, no toe/heel); its step_time_s is the initial double support.
    """

    leg: str  # "rleg" | "lleg"
    x: float  # [m]
    y: float  # [m]
    z: float = 0.0  # [m]
    yaw: float = 0.0  # [rad]
    roll: float = 0.0  # [rad]
    pitch: float = 0.0  # [rad]
    step_height_m: float = 0.05  # swing height above the line src -> dst [m]
    step_time_s: float = 1.0  # duration of the step ending here, double supports included [s]
    toe_angle_rad: float = 0.0  # toe-off pitch reached in phase (ii) [rad], >= 0
    heel_angle_rad: float = 0.0  # heel-contact pitch (applied as -heel) in phase (iii) [rad], >= 0

    def __post_init__(self) -> None:
        _check_leg(self.leg)
        if not self.step_time_s > 0.0:
            raise InvalidCommand(f"Footstep.step_time_s={self.step_time_s!r} [s]; must be > 0")
        if self.step_height_m < 0.0 or self.toe_angle_rad < 0.0 or self.heel_angle_rad < 0.0:
            raise InvalidCommand("Footstep step_height_m, toe_angle_rad and heel_angle_rad must be >= 0 "
                                 f"(got {self.step_height_m}, {self.toe_angle_rad}, {self.heel_angle_rad})")

    @property
    def position(self) -> np.ndarray:  # (3,) [m]
        return np.array([self.x, self.y, self.z])

    @property
    def rpy(self) -> np.ndarray:  # (3,) [rad]
        return np.array([self.roll, self.pitch, self.yaw])

    @property
    def T_world_foot(self) -> np.ndarray:  # (4, 4)
        T = np.eye(4)
        T[:3, :3] = rpy_to_matrix(self.rpy)
        T[:3, 3] = self.position
        return T

    @classmethod
    def from_T(cls, leg: str, T_world_foot: np.ndarray, **step_params) -> Footstep:
        roll, pitch, yaw = matrix_to_rpy(np.asarray(T_world_foot)[:3, :3])
        x, y, z = np.asarray(T_world_foot)[:3, 3]
        return cls(leg, float(x), float(y), float(z), float(yaw), float(roll), float(pitch), **step_params)

    def replaced(self, **changes) -> Footstep:
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class StepParams(Params):
    """Per-step swing parameters (hrpsys step_height, step_time, toe_angle, heel_angle)."""

    step_height_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.5})
    step_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.05, "max": 10.0})
    toe_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 1.0})
    heel_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 1.0})


@dataclass(frozen=True)
class FootstepParams(Params):
    """Defaults of the footstep planners (hrpsys GaitGenerator defaults, HRP-2 feet at y = +-0.095 m)."""

    leg_offset_y_m: float = field(default=0.095, metadata={"unit": "m", "min": 0.0, "max": 0.5})  # foot from mid
    step_height_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.5})
    step_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.05, "max": 10.0})
    toe_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 1.0})
    heel_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 1.0})
    lookahead_steps: int = field(default=3, metadata={"unit": "-", "min": 1, "max": 10})  # goVelocity

    @property
    def step(self) -> StepParams:
        return StepParams(self.step_height_m, self.step_time_s, self.toe_angle_rad, self.heel_angle_rad)


@dataclass(frozen=True)
class StrideLimits(Params):
    """Largest displacement of the feet mid-coords per step, in its own frame (hrpsys SQUARE limits).

    "inside" applies when the swing foot moves towards the support foot (y, yaw), "outside" away from it.
    """

    fwd_x_m: float = field(default=0.15, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    outside_y_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    outside_th_rad: float = field(default=math.radians(10.0), metadata={"unit": "rad", "min": 0.0, "max": 1.6})
    bwd_x_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    inside_y_m: float = field(default=0.025, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    inside_th_rad: float = field(default=math.radians(5.0), metadata={"unit": "rad", "min": 0.0, "max": 1.6})


# --- planar poses (x [m], y [m], yaw [rad]) -------------------------------------------------------------


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def _compose(a: tuple, b: tuple) -> tuple[float, float, float]:
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], _wrap(a[2] + b[2]))


def _relative(a: tuple, b: tuple) -> tuple[float, float, float]:
    """a^-1 b: b expressed in the frame of a."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, _wrap(b[2] - a[2]))


def _leg_sign(leg: str) -> float:
    return 1.0 if leg == "lleg" else -1.0


def mid_coords(rfoot: Footstep, lfoot: Footstep) -> tuple[float, float, float]:
    """Planar mid-coords (x [m], y [m], yaw [rad]) of two feet (mean position, half-way yaw)."""
    yaw = _wrap(rfoot.yaw + 0.5 * _wrap(lfoot.yaw - rfoot.yaw))
    return (0.5 * (rfoot.x + lfoot.x), 0.5 * (rfoot.y + lfoot.y), yaw)


def clamp_stride(d: Sequence[float], swing_leg: str, limits: StrideLimits) -> tuple[float, float, float]:
    """Mid-coords displacement (dx [m], dy [m], dth [rad]) clamped by the limits for this swing leg."""
    sign = _leg_sign(swing_leg)  # +1: the left foot swings, moving +y / +yaw is outward
    lo_y, hi_y = -limits.inside_y_m, limits.outside_y_m
    lo_th, hi_th = -limits.inside_th_rad, limits.outside_th_rad
    if sign < 0.0:
        lo_y, hi_y, lo_th, hi_th = -hi_y, -lo_y, -hi_th, -lo_th
    return (min(max(d[0], -limits.bwd_x_m), limits.fwd_x_m), min(max(d[1], lo_y), hi_y),
            min(max(d[2], lo_th), hi_th))


def _foot_at(mid: tuple, leg: str, z: float, params: FootstepParams, step: StepParams | None = None) -> Footstep:
    x, y, yaw = (float(v) for v in _compose(mid, (0.0, _leg_sign(leg) * params.leg_offset_y_m, 0.0)))
    step = step or params.step
    return Footstep(leg, x, y, float(z), yaw, step_height_m=step.step_height_m, step_time_s=step.step_time_s,
                    toe_angle_rad=step.toe_angle_rad, heel_angle_rad=step.heel_angle_rad)


def _first_node(foot: Footstep, params: FootstepParams) -> Footstep:
    return foot.replaced(step_height_m=0.0, toe_angle_rad=0.0, heel_angle_rad=0.0, step_time_s=params.step_time_s)


def _planar_close(a: Footstep, b: Footstep) -> bool:
    return (math.hypot(a.x - b.x, a.y - b.y) < _ALIGNED_TOL and abs(_wrap(a.yaw - b.yaw)) < _ALIGNED_TOL
            and abs(a.z - b.z) < _ALIGNED_TOL)


def _align(steps: list[Footstep], mids: list[tuple], goal: tuple, z: float, params: FootstepParams) -> None:
    """Append one aligning step, and a second one if the other foot is not at `goal` yet (hrpsys)."""
    steps.append(_foot_at(goal, other_leg(steps[-1].leg), z, params))
    mids.append(goal)
    last_of_other = next(f for f in reversed(steps) if f.leg != steps[-1].leg)
    target = _foot_at(goal, last_of_other.leg, z, params)
    if not _planar_close(last_of_other, target):
        steps.append(target)
        mids.append(goal)


def go_pos(T_world_rfoot: np.ndarray, T_world_lfoot: np.ndarray, dx_m: float, dy_m: float, dtheta_rad: float,
           params: FootstepParams | None = None, limits: StrideLimits | None = None) -> list[Footstep]:
    """hrpsys goPos: footsteps from the current feet to their mid-coords composed with (dx, dy, dtheta).

    Node 0 is the current support foot (rleg if dy > 0 else lleg) with zero height. Each following step
    moves the mid-coords by the remaining displacement clamped by the stride limits (hrpsys velocity mode
    with v = remaining / step_time) until less than 0.1 mm and 0.5 deg remain; then one (or two) aligning
    steps put both feet side by side at the goal mid-coords.
    """
    params = params or FootstepParams()
    limits = limits or StrideLimits()
    rfoot, lfoot = Footstep.from_T("rleg", T_world_rfoot), Footstep.from_T("lleg", T_world_lfoot)
    start = mid_coords(rfoot, lfoot)
    z = 0.5 * (rfoot.z + lfoot.z)
    goal = _compose(start, (dx_m, dy_m, dtheta_rad))
    support = "rleg" if dy_m > 0.0 else "lleg"
    steps = [_first_node(rfoot if support == "rleg" else lfoot, params)]
    _walk_to(steps, [start], goal, z, params, limits)
    return steps


def go_pos_from(kept: Sequence[Footstep], goal_mid: Sequence[float], params: FootstepParams | None = None,
                limits: StrideLimits | None = None) -> list[Footstep]:
    """hrpsys goPos while walking: `kept` (the footsteps not replaced, the last one the support foot of the
    first new step) followed by the steps to the mid-coords `goal_mid` (x [m], y [m], yaw [rad], world).

    As hrpsys, the walk goes on from the mid-coords under the last kept footstep (that foot moved back by
    its leg offset), with the same clamped steps and aligning steps as `go_pos`."""
    params = params or FootstepParams()
    limits = limits or StrideLimits()
    if not kept:
        raise InvalidCommand("go_pos_from needs at least one kept footstep (the support foot)")
    steps = list(kept)
    last = steps[-1]
    start = _compose((last.x, last.y, last.yaw), (0.0, -_leg_sign(last.leg) * params.leg_offset_y_m, 0.0))
    goal = (float(goal_mid[0]), float(goal_mid[1]), _wrap(float(goal_mid[2])))
    _walk_to(steps, [start], goal, last.z, params, limits)
    return steps


def stop_after(kept: Sequence[Footstep], params: FootstepParams | None = None,
               limits: StrideLimits | None = None) -> list[Footstep]:
    """goStop in a goPos or footstep walk: `kept` (the committed footsteps) then the aligning step that puts the
    other foot beside the last one (go_pos_from to the mid-coords under it)."""
    params = params or FootstepParams()
    last = kept[-1]
    mid = _compose((last.x, last.y, last.yaw), (0.0, -_leg_sign(last.leg) * params.leg_offset_y_m, 0.0))
    return go_pos_from(kept, mid, params, limits)


def _walk_to(steps: list[Footstep], mids: list[tuple], goal: tuple, z: float, params: FootstepParams,
             limits: StrideLimits) -> None:
    """Append clamped steps from mids[-1] until the goal mid-coords is reached, then the aligning step(s)."""
    mid = mids[-1]
    for _ in range(10000):
        rem = _relative(mid, goal)
        if math.hypot(rem[0], rem[1]) < _GO_POS_POS_TOL_M and abs(rem[2]) < _GO_POS_TH_TOL_RAD:
            break
        swing = other_leg(steps[-1].leg)
        mid = _compose(mid, clamp_stride(rem, swing, limits))
        steps.append(_foot_at(mid, swing, z, params))
        mids.append(mid)
    else:  # pragma: no cover - the clamped steps always converge
        raise InvalidCommand(f"goPos to the mid-coords {goal} did not converge")
    _align(steps, mids, goal, z, params)


def capped_stride_limits(limits: StrideLimits, max_stride_m: float | None) -> StrideLimits:
    """The limits with every translation (forward, backward, outside, inside) capped at `max_stride_m`
    [m], the step length limit [OP] V-A lets the operator set; None: the limits as they are."""
    if max_stride_m is None:
        return limits
    m = float(max_stride_m)
    return limits.replaced(fwd_x_m=min(limits.fwd_x_m, m), bwd_x_m=min(limits.bwd_x_m, m),
                           outside_y_m=min(limits.outside_y_m, m), inside_y_m=min(limits.inside_y_m, m))


def set_footsteps(footsteps: Sequence[tuple], T_world_rfoot: np.ndarray, T_world_lfoot: np.ndarray,
                  params: FootstepParams | None = None,
                  step_params: Sequence[StepParams | None] | None = None) -> list[Footstep]:
    """hrpsys setFootSteps: `(leg, pos (3,) [m], rpy (3,) [rad])` inputs re-expressed relative to the first one,
    which is snapped onto the current pose of its leg. Node 0 gets zero height and no toe/heel; the others
    the defaults of `params` or their own `step_params[i]`.
    """
    params = params or FootstepParams()
    if len(footsteps) == 0:
        raise InvalidCommand("set_footsteps needs at least one footstep (the current support foot)")
    if step_params is not None and len(step_params) != len(footsteps):
        raise InvalidCommand(f"step_params has {len(step_params)} entries; expected one per footstep "
                             f"({len(footsteps)}) or None")
    inputs = []
    for item in footsteps:
        if len(item) != 3:
            raise InvalidCommand(f"a footstep is (leg, pos, rpy); got {item!r}")
        leg, pos, rpy = item
        _check_leg(leg)
        T = np.eye(4)
        T[:3, :3] = rpy_to_matrix(np.asarray(rpy, dtype=float))
        T[:3, 3] = np.asarray(pos, dtype=float)
        inputs.append((leg, T))
    T_current = {"rleg": np.asarray(T_world_rfoot, float), "lleg": np.asarray(T_world_lfoot, float)}
    T_snap = T_current[inputs[0][0]] @ np.linalg.inv(inputs[0][1])
    out = []
    for i, (leg, T) in enumerate(inputs):
        step = (step_params[i] if step_params is not None else None) or params.step
        out.append(Footstep.from_T(leg, T_snap @ T, step_height_m=step.step_height_m,
                                   step_time_s=step.step_time_s, toe_angle_rad=step.toe_angle_rad,
                                   heel_angle_rad=step.heel_angle_rad))
    out[0] = out[0].replaced(step_height_m=0.0, toe_angle_rad=0.0, heel_angle_rad=0.0)
    return out


def stop_in_place(landed: Footstep, other: Footstep, count: int = 3) -> list[Footstep]:
    """hrpsys emergency stop: `count` zero-height steps on the current feet, starting with `other`'s leg."""
    feet = [other, landed]
    return [feet[i % 2].replaced(step_height_m=0.0, toe_angle_rad=0.0, heel_angle_rad=0.0) for i in range(count)]


class VelocityStepper:
    """hrpsys velocity mode: keeps `lookahead_steps` footsteps ahead for a commanded (vx, vy, vtheta).

    `footsteps[:index]` have landed and `footsteps[index]` is being stepped on (`advance_to`); steps from
    the overwritable index `index + 1` on are recomputed by `replan()` (new velocity), replaced by aligning
    steps by `finalize()` (goStop) or by steps in place by `emergency_stop()`.
    """

    def __init__(self, T_world_rfoot: np.ndarray, T_world_lfoot: np.ndarray,
                 params: FootstepParams | None = None, limits: StrideLimits | None = None) -> None:
        self.params = params or FootstepParams()
        self.limits = limits or StrideLimits()
        self._rfoot = Footstep.from_T("rleg", T_world_rfoot)
        self._lfoot = Footstep.from_T("lleg", T_world_lfoot)
        self._z = 0.5 * (self._rfoot.z + self._lfoot.z)
        self._velocity = (0.0, 0.0, 0.0)  # (vx [m/s], vy [m/s], vtheta [rad/s]) in the mid-coords frame
        self._steps: list[Footstep] = []
        self._mids: list[tuple[float, float, float]] = []
        self._index = 0
        self.state = "idle"  # "idle" | "walking" | "ending" | "stopped"

    def __repr__(self) -> str:
        return (f"VelocityStepper(state={self.state!r}, velocity={self._velocity}, index={self._index}, "
                f"footsteps={len(self._steps)})")

    @property
    def footsteps(self) -> tuple[Footstep, ...]:
        return tuple(self._steps)

    @property
    def velocity(self) -> tuple[float, float, float]:
        return self._velocity

    @property
    def overwritable_index(self) -> int:
        return self._index + 1

    def start(self, vx_m_s: float, vy_m_s: float, vtheta_rad_s: float) -> list[Footstep]:
        """Node 0 (support = rleg if vy > 0 else lleg) plus `lookahead_steps` velocity steps."""
        self._velocity = (float(vx_m_s), float(vy_m_s), float(vtheta_rad_s))
        support = self._rfoot if vy_m_s > 0.0 else self._lfoot
        self._steps = [_first_node(support, self.params)]
        self._mids = [mid_coords(self._rfoot, self._lfoot)]
        self._index = 0
        self.state = "walking"
        return self.replan()

    def set_velocity(self, vx_m_s: float, vy_m_s: float, vtheta_rad_s: float) -> None:
        """New velocity for the steps computed at the next `replan()` (hrpsys: at the mid-step check)."""
        self._velocity = (float(vx_m_s), float(vy_m_s), float(vtheta_rad_s))

    def set_params(self, params: FootstepParams, limits: StrideLimits) -> None:
        """New step parameters and stride limits for the steps computed from the next `replan()` on."""
        self.params = params
        self.limits = limits

    def resume(self) -> None:
        """Back from "ending" (goStop asked, the aligning steps not yet replaced) to "walking": the next
        `replan()` puts velocity steps after the overwritable index again. No effect in other states."""
        if self.state == "ending":
            self.state = "walking"

    def advance_to(self, index: int) -> None:
        """`footsteps[index]` is now being stepped on; everything before it has landed."""
        if not 0 <= index < len(self._steps):
            raise InvalidCommand(f"advance_to({index}); valid: 0..{len(self._steps) - 1}")
        self._index = index

    def remaining(self) -> list[Footstep]:
        """Footsteps not landed yet (the one being stepped on included)."""
        return list(self._steps[self._index:])

    def _truncate(self) -> int:
        k = self.overwritable_index
        del self._steps[k:]
        del self._mids[k:]
        return k

    def replan(self) -> list[Footstep]:
        """Recompute the steps after the overwritable index with the current velocity (no-op once ending)."""
        if self.state != "walking":
            return list(self._steps)
        self._truncate()
        T = self.params.step_time_s
        for _ in range(self.params.lookahead_steps):
            swing = other_leg(self._steps[-1].leg)
            d = clamp_stride(tuple(v * T for v in self._velocity), swing, self.limits)
            mid = _compose(self._mids[-1], d)
            self._steps.append(_foot_at(mid, swing, self._z, self.params))
            self._mids.append(mid)
        return list(self._steps)

    def finalize(self) -> list[Footstep]:
        """goStop: after the overwritable index, only the aligning step(s) at the current mid-coords."""
        if self.state == "walking":
            self._truncate()
            _align(self._steps, self._mids, self._mids[-1], self._z, self.params)
            self.state = "ending"
        return list(self._steps)

    def emergency_stop(self) -> list[Footstep]:
        """emergencyStop: after the overwritable index, steps in place on the current feet (then nothing)."""
        if self.state in ("walking", "ending"):
            k = self._truncate()
            landed = self._steps[k - 1]
            other = next((f for f in reversed(self._steps[: k - 1]) if f.leg != landed.leg), None)
            if other is None:  # still on node 0: the other foot has not moved
                other = (self._lfoot if landed.leg == "rleg" else self._rfoot).replaced(
                    step_time_s=self.params.step_time_s)
            self._steps += stop_in_place(landed, other)
            self._mids += [self._mids[-1]] * 3
            self.state = "stopped"
        return list(self._steps)
