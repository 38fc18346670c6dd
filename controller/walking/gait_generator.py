"""Walking plan sampled per tick: reference ZMP (Eq. 4, toe-heel), both foot poses, support state, ZMP preview."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.layer import Params
from controller.core.types import read_only
from controller.interpolation.hoff_arbib import min_jerk
from controller.walking.footsteps import (
    Footstep,
    FootstepParams,
    StepParams,
    StrideLimits,
    VelocityStepper,
    capped_stride_limits,
    go_pos,
    go_pos_from,
    mid_coords,
    other_leg,
    set_footsteps,
    stop_in_place,
)
from controller.walking.swing_trajectory import ORBIT_TYPES, swing_position, swing_rpy
from controller.walking.toe_heel import ToeHeelParams, cop_offset_x, foot_pitch_offset

__all__ = ["GaitGenerator", "GaitParams", "GaitPatch", "GaitSample"]

_R, _L = 0, 1  # foot index in the (2, ...) arrays
_SUPPORT_NAMES = ("rleg", "lleg", "both")
_BOTH = 2
#: [s] the final double support of a stop from rest: the ZMP (and the COG with it) moves to the feet's middle
REST_STOP_DOUBLE_SUPPORT_S = 2.0


@dataclass(frozen=True)
class GaitParams(Params):
    """Timing and ZMP of the walking plan (hrpsys GaitGenerator defaults)."""

    # ZMP moves foot to foot over the last `after` and the first `before` fraction of the step times
    double_support_ratio_before: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    double_support_ratio_after: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    orbit_type: str = field(default="cycloid", metadata={"choices": ORBIT_TYPES})
    # hrpsys default_zmp_offsets: each foot's COP in its sole frame [m]
    rleg_zmp_offset_x_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    rleg_zmp_offset_y_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    lleg_zmp_offset_x_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    lleg_zmp_offset_y_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    # duration of the final double support that brings the ZMP back to the feet mid-coords [s]
    final_double_support_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.05, "max": 10.0})
    preview_time_s: float = field(default=1.6, metadata={"unit": "s", "min": 0.0, "max": 10.0})  # ZMP preview


@dataclass(frozen=True, slots=True)
class GaitSample:
    """The plan at one tick (world frame; foot = sole frame, see `Footstep`)."""

    time_s: float  # since the plan started [s]
    walking: bool
    support: str  # "rleg" | "lleg" | "both"
    footstep_index: int  # footstep being stepped on (0: initial double support, len(footsteps): final)
    remaining_footsteps: int  # footsteps not landed yet
    zmp_world: np.ndarray  # (3,) reference ZMP, Eq. 4 [m]
    p_rfoot_world: np.ndarray  # (3,) [m]
    R_rfoot_world: np.ndarray  # (3, 3)
    p_lfoot_world: np.ndarray  # (3,) [m]
    R_lfoot_world: np.ndarray  # (3, 3)
    r_lleg: float  # Eq. 4 weight of the left foot COP [-]
    cop_offset_x_m: np.ndarray  # (2,) (rleg, lleg) toe-heel COP offset along the sole x [m]
    pitch_offset_rad: np.ndarray  # (2,) (rleg, lleg) toe-heel foot pitch offset [rad]

    @property
    def contact(self) -> tuple[bool, bool]:  # (right, left) soles meant to be on the ground
        return (self.support != "lleg", self.support != "rleg")


@dataclass(frozen=True, slots=True)
class GaitPatch:
    """A change of the plan computed ahead (GaitGenerator.prepare_set_zmp / prepare_move_swing), nothing changed
    yet; `GaitGenerator.apply` puts it in while the plan is still the one it was computed from."""

    source: tuple  # (sample arrays, next tick, plan version, params) it was computed from, compared by identity
    arrays: dict  # the sample arrays after the change
    #: a moved landing: (segment index, the footstep moved, its segment's end pose (2, 6), a copy of it)
    landing: tuple | None = None


@dataclass
class _Segment:
    """One footstep's share of the plan: "start" (initial double support), "step", or "end"."""

    kind: str
    index: int  # footstep index (len(footsteps) for "end")
    duration_s: float
    n_ticks: int
    start_tick: int  # absolute tick of its first sample
    q_start: np.ndarray  # (2, 6) feet (x, y, z, roll, pitch, yaw) at its start
    q_end: np.ndarray | None = None
    # the GaitParams the segment was planned with: a parameter change applies to the segments planned
    # after it, a replan that resamples this segment keeps its timing (no jump of the ZMP mid-step)
    params: GaitParams | None = None


def _rpy_matrices(rpy: np.ndarray) -> np.ndarray:
    """(n, 3, 3) R = Rz(yaw) Ry(pitch) Rx(roll) for (n, 3) roll-pitch-yaw [rad]."""
    r, p, y = rpy[:, 0], rpy[:, 1], rpy[:, 2]
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.stack([
        np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=-1),
        np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=-1),
        np.stack([-sp, cp * sr, cp * cr], axis=-1),
    ], axis=1)


def _ry(theta: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    z, o = np.zeros_like(theta), np.ones_like(theta)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], axis=1)


def _compose_planar(a: tuple, b: tuple) -> tuple[float, float, float]:
    """Planar pose a composed with b: (x [m], y [m], yaw [rad])."""
    c, s = np.cos(a[2]), np.sin(a[2])
    yaw = (a[2] + b[2] + np.pi) % (2.0 * np.pi) - np.pi
    return (float(a[0] + c * b[0] - s * b[1]), float(a[1] + s * b[0] + c * b[1]), float(yaw))


def _relative_planar(a: tuple, b: tuple) -> tuple[float, float, float]:
    """b in the frame of a: (x [m], y [m], yaw [rad])."""
    c, s = np.cos(a[2]), np.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    yaw = (b[2] - a[2] + np.pi) % (2.0 * np.pi) - np.pi
    return (float(c * dx + s * dy), float(-s * dx + c * dy), float(yaw))


def _q_of(step: Footstep) -> np.ndarray:
    return np.array([step.x, step.y, step.z, step.roll, step.pitch, step.yaw])


class GaitGenerator:
    """hrpsys GaitGenerator's planning half: footsteps in, per-tick reference ZMP and foot poses out.

    `plan` / the go_* commands sample the whole plan at once (vectorised, a few ms); a replan (goVelocity
    update at mid-step, goStop, emergencyStop) resamples only from the overwritable footstep on. `tick()`
    then only slices precomputed arrays, and `zmp_preview(n)` returns the next n reference ZMPs.
    """

    def __init__(self, params: GaitParams | None = None, dt_s: float = 0.005,
                 T_world_rfoot: np.ndarray | None = None, T_world_lfoot: np.ndarray | None = None,
                 footstep_params: FootstepParams | None = None, stride_limits: StrideLimits | None = None,
                 toe_heel: ToeHeelParams | None = None) -> None:
        if not dt_s > 0.0:
            raise InvalidCommand(f"dt_s={dt_s!r} [s]; must be > 0")
        self.params = params or GaitParams()
        self.footstep_params = footstep_params or FootstepParams()
        self.stride_limits = stride_limits or StrideLimits()
        self.toe_heel = toe_heel or ToeHeelParams()
        self.dt_s = float(dt_s)
        y = self.footstep_params.leg_offset_y_m
        self._feet = {"rleg": Footstep("rleg", 0.0, -y), "lleg": Footstep("lleg", 0.0, y)}
        if T_world_rfoot is not None:
            self._feet["rleg"] = Footstep.from_T("rleg", T_world_rfoot)
        if T_world_lfoot is not None:
            self._feet["lleg"] = Footstep.from_T("lleg", T_world_lfoot)
        p = self.params
        self._zmp_offsets = np.array([[p.rleg_zmp_offset_x_m, p.rleg_zmp_offset_y_m, 0.0],
                                      [p.lleg_zmp_offset_x_m, p.lleg_zmp_offset_y_m, 0.0]])  # (2, 3) [m]
        self._footsteps: list[Footstep] = []
        self._segments: list[_Segment] = []
        self._stepper: VelocityStepper | None = None
        self._walking = False
        self._tick = 0  # absolute index of the next sample
        self._end_tick = 0
        self._origin = 0  # absolute tick of row 0 of the sample arrays
        self._arrays: dict[str, np.ndarray] | None = None
        self._checks: dict[int, int] = {}  # absolute tick -> segment index of the mid-step overwrite checks
        self._stopping_from_rest = False  # the rest of the walk is a stop_from_rest plan
        self._plan_version = 0
        self._rest_from: tuple | None = None  # the pose stop_from_rest planned from (feet p, R, support, footstep)
        self._walk_origin = mid_coords(self._feet["rleg"], self._feet["lleg"])  # (x, y, yaw) where the walk began
        self._pending_goal: tuple[float, float, float] | None = None  # goPos goal mid-coords for after this walk
        self._pending_velocity: tuple[float, float, float] | None = None  # goVelocity for after this walk
        self._velocity_step: tuple[float | None, float | None] = (None, None)  # (max stride, foot distance) [m]
        self._plan_params: GaitParams | None = None  # the plan's own timing (an emergency step's), else params
        self._swing_end: tuple[np.ndarray, int, int] | None = None  # swing_samples_left's last search
        self._idle = self._idle_sample()

    def __repr__(self) -> str:
        return (f"GaitGenerator(dt_s={self.dt_s}, walking={self._walking}, footsteps={len(self._footsteps)}, "
                f"tick={self._tick}, params={self.params!r})")

    # ----- state ----------------------------------------------------------------------------------------

    @property
    def walking(self) -> bool:
        return self._walking

    @property
    def footsteps(self) -> tuple[Footstep, ...]:
        return tuple(self._footsteps)

    @property
    def plan_version(self) -> int:
        """Changes whenever the footstep list is replaced (a new plan or a replan): a cache key."""
        return self._plan_version

    @property
    def T_world_rfoot(self) -> np.ndarray:  # (4, 4) where the right foot stands when idle
        return self._feet["rleg"].T_world_foot

    @property
    def T_world_lfoot(self) -> np.ndarray:
        return self._feet["lleg"].T_world_foot

    @property
    def walk_origin(self) -> tuple[float, float, float]:
        """Mid-coords (x [m], y [m], yaw [rad], world) of the feet where the current (or last) walk began:
        what goPos while walking is relative to (hrpsys initial_foot_mid_coords)."""
        return self._walk_origin

    @property
    def velocity_mode(self) -> str:
        """"idle" (no velocity walk), "walking", "ending" (goStop asked) or "stopped" (emergency stop)."""
        if not self._walking or self._stepper is None:
            return "idle"
        return self._stepper.state

    @property
    def stopping_from_rest(self) -> bool:
        """The rest of the walk is the stop from rest planned after the hard e-stop (nothing may replan it)."""
        return self._walking and self._stopping_from_rest

    def remaining_footsteps(self) -> list[Footstep]:
        """Footsteps not landed yet (the one being stepped on included)."""
        if not self._walking:
            return []
        return self._footsteps[max(self._current_segment().index, 1):]

    def swing_samples_left(self) -> int:
        """Samples of the swing in progress from the one `tick()` handed out last to the touchdown (that one
        counted): the swing foot is planned down from that many ticks on; 0 in double support or idle."""
        if not self._walking:
            return 0
        support = self._arrays["support"]
        j = self._tick - 1 - self._origin
        if not 0 <= j < len(support) or support[j] == _BOTH:
            return 0
        cache = self._swing_end  # (the support array, the swing's first and end sample): one search per swing
        if cache is None or cache[0] is not support or not cache[1] <= j < cache[2]:
            other = np.flatnonzero(support[j:] != support[j])
            cache = self._swing_end = (support, j, j + (int(other[0]) if len(other) else len(support) - j))
        return cache[2] - j

    # ----- commands (planning) --------------------------------------------------------------------------

    def plan(self, footsteps: Sequence[Footstep], params: GaitParams | None = None) -> None:
        """Start walking on `footsteps`; footsteps[0] must be the current pose of its leg (the support foot).

        `params`: timing and ZMP of this plan only (an emergency step's short double supports), kept by its
        replans; None: the generator's `params`."""
        if self._walking:
            raise InvalidState("already walking: use go_velocity / go_stop / emergency_stop, or wait for the end")
        footsteps = list(footsteps)
        if not footsteps:
            raise InvalidCommand("plan needs at least footsteps[0], the current support foot")
        first, current = footsteps[0], self._feet[footsteps[0].leg]
        if np.max(np.abs(first.T_world_foot - current.T_world_foot)) > 1e-6:
            raise InvalidCommand(f"footsteps[0] ({first.leg}) must be at the current {first.leg} pose "
                                 f"{current.position.tolist()}; build it with go_pos/set_footsteps from the feet")
        self._footsteps = footsteps
        self._plan_version += 1
        self._stopping_from_rest = False
        self._plan_params = params
        self._walk_origin = mid_coords(self._feet["rleg"], self._feet["lleg"])
        q0 = np.stack([_q_of(self._feet["rleg"]), _q_of(self._feet["lleg"])])
        self._segments = [_Segment("start", 0, first.step_time_s, self._n_ticks(first.step_time_s), 0, q0,
                                   params=params or self.params)]
        self._tick = self._origin = 0
        self._arrays = None
        self._walking = True
        self._resample_from(0)

    def go_pos(self, dx_m: float, dy_m: float, dtheta_rad: float) -> list[Footstep]:
        """hrpsys goPos: from rest, to the current feet's mid-coords composed with (dx, dy, dtheta).

        While walking (a goPos, a footstep list or velocity mode), as hrpsys does, the goal is relative to
        where this walk began (`walk_origin`) and it replaces the rest of the plan from the next free
        footstep: the one after the footstep being stepped on, or the one after that once the current
        step's mid-step check has passed (its successor's ZMP is then committed, as in hrpsys). When no
        footstep is free any more (the last step's second half, the final double support) the new walk
        starts from the feet where this one ends. Returns the footsteps planned (the new plan; empty when
        it waits for the end of the walk)."""
        if not self._walking:
            steps = go_pos(self.T_world_rfoot, self.T_world_lfoot, dx_m, dy_m, dtheta_rad,
                           self.footstep_params, self.stride_limits)
            self._stepper = None
            self.plan(steps)
            return steps
        if self._stopping_from_rest:
            raise InvalidState("the walk is ending (a stop from rest after the e-stop): goPos once it stands")
        goal = _compose_planar(self._walk_origin, (dx_m, dy_m, dtheta_rad))
        k = self._free_index()
        if k > len(self._footsteps):
            self._pending_goal, self._pending_velocity = goal, None
            return []
        steps = go_pos_from(self._footsteps[:k], goal, self.footstep_params, self.stride_limits)
        self._stepper = None
        self.replan(steps, k)
        return steps

    def set_footsteps(self, footsteps: Sequence[tuple], step_params: Sequence[StepParams | None] | None = None
                      ) -> list[Footstep]:
        """hrpsys setFootSteps: `(leg, pos [m], rpy [rad])` relative to the first, snapped to the current foot."""
        steps = set_footsteps(footsteps, self.T_world_rfoot, self.T_world_lfoot, self.footstep_params, step_params)
        self._stepper = None
        self.plan(steps)
        return steps

    def go_velocity(self, vx_m_s: float, vy_m_s: float, vtheta_rad_s: float) -> None:
        """hrpsys goVelocity: start velocity mode, or change the velocity of the steps planned at the next
        mid-step check (the gait goes on; nothing restarts). After goStop, while the aligning steps are not
        being stepped yet, the walk resumes at the new velocity instead of ending."""
        if self._walking:
            if self._stepper is None or self._stepper.state not in ("walking", "ending"):
                raise InvalidState("walking a fixed footstep list: go_velocity needs idle or velocity mode")
            if self._stepper.state == "ending" and not any(t >= self._tick for t in self._checks):
                self._pending_velocity = (vx_m_s, vy_m_s, vtheta_rad_s)  # no check left to resume at: after it
                return
            self._stepper.resume()
            self._stepper.set_velocity(vx_m_s, vy_m_s, vtheta_rad_s)
            return
        self._pending_goal = self._pending_velocity = None
        self._stepper = VelocityStepper(self.T_world_rfoot, self.T_world_lfoot, *self._velocity_params())
        self.plan(self._stepper.start(vx_m_s, vy_m_s, vtheta_rad_s))

    def set_velocity_step(self, max_stride_m: float | None, foot_distance_m: float | None) -> None:
        """The walking point's step parameters ([OP] V-A) for the velocity steps planned from now on: the step
        length limit [m] (caps the stride limits' translations) and the distance between the feet's centres
        [m]; None keeps the footstep parameters' own."""
        if (max_stride_m, foot_distance_m) == self._velocity_step:
            return
        if max_stride_m is not None and not max_stride_m >= 0.0:
            raise InvalidCommand(f"max_stride_m={max_stride_m!r} [m]; must be >= 0")
        if foot_distance_m is not None and not foot_distance_m > 0.0:
            raise InvalidCommand(f"foot_distance_m={foot_distance_m!r} [m]; must be > 0")
        self._velocity_step = (max_stride_m, foot_distance_m)
        if self._stepper is not None:
            self._stepper.set_params(*self._velocity_params())

    def configure(self, params: GaitParams | None = None, footstep_params: FootstepParams | None = None,
                  stride_limits: StrideLimits | None = None) -> None:
        """hrpsys setGaitGeneratorParam: new timing/ZMP, step and stride parameters, applied to the footsteps
        and segments planned from now on (what is planned already, and the velocity steps up to the next
        mid-step check, keep theirs)."""
        if params is not None:
            self.params = params
            p = params
            self._zmp_offsets = np.array([[p.rleg_zmp_offset_x_m, p.rleg_zmp_offset_y_m, 0.0],
                                          [p.lleg_zmp_offset_x_m, p.lleg_zmp_offset_y_m, 0.0]])
            if not self._walking:
                self._idle = self._idle_sample()
        if footstep_params is not None:
            self.footstep_params = footstep_params
        if stride_limits is not None:
            self.stride_limits = stride_limits
        if self._stepper is not None:
            self._stepper.set_params(*self._velocity_params())

    def _velocity_params(self) -> tuple[FootstepParams, StrideLimits]:
        """The footstep parameters and stride limits of velocity steps: the gait's with the walking point's."""
        max_stride, distance = self._velocity_step
        params = self.footstep_params
        if distance is not None:
            params = params.replaced(leg_offset_y_m=0.5 * distance)
        return params, capped_stride_limits(self.stride_limits, max_stride)

    def go_stop(self) -> None:
        """hrpsys goStop: in velocity mode, the steps after the overwritable one become the aligning steps
        (a goPos waiting for the end of the walk is dropped)."""
        self._pending_goal = self._pending_velocity = None
        if self._walking and self._stepper is not None and self._stepper.state == "walking":
            k = self._overwritable_index()
            if k > len(self._footsteps):
                return  # already in the final double support
            self._stepper.advance_to(k - 1)
            self.replan(self._stepper.finalize(), k)

    def emergency_stop(self) -> None:
        """hrpsys emergencyStop: the steps after the overwritable one are replaced by steps in place."""
        self._pending_goal = self._pending_velocity = None
        if not self._walking or self._stopping_from_rest:
            return
        k = self._overwritable_index()
        if k > len(self._footsteps):
            return  # already in the final double support
        if k == len(self._footsteps):
            # the step in progress is the plan's last: the walk ends on its landing anyway, and steps in place
            # after it would swing the CP back across the feet (campaign seed 2006: a turning goPos fell)
            return
        if self._stepper is not None:
            self._stepper.advance_to(k - 1)
            self.replan(self._stepper.emergency_stop(), k)
            return
        steps = self._footsteps[:k]
        landed = steps[-1]
        q_other = self._segments[k - 1].q_start[_L if landed.leg == "rleg" else _R]
        x, y, z, roll, pitch, yaw = (float(v) for v in q_other)
        other = Footstep(other_leg(landed.leg), x, y, z, yaw, roll, pitch,
                         step_time_s=self.footstep_params.step_time_s)
        self.replan(steps + stop_in_place(landed.replaced(step_time_s=other.step_time_s), other), k)

    def stop_from_rest(self, zmp_world_xy: Sequence[float], swing_foot_loaded: bool = False,
                       landing_speed_m_s: float = 0.05, min_landing_time_s: float = 0.8) -> float:
        """Replace what is left of the walk by a stop that starts from rest where the plan is now: for a
        robot that was held still mid-walk (the hard e-stop), so its COG is at rest above `zmp_world_xy`.

        In single support the swing foot goes straight down to where its footstep lands it in height and
        tilt (x, y and yaw where it is now), at `landing_speed_m_s` or over `min_landing_time_s`, with the
        ZMP kept at `zmp_world_xy`; then a final double support brings the ZMP to the feet's mid-point.
        `swing_foot_loaded`: the held robot has tipped onto its swing foot; the landing is then a double
        support already, the ZMP moving to the mid-point all along. In double support only that final
        double support remains (the feet stay where they are). Called again before the next tick, it
        replans from the same pose (e.g. once the robot's measured state is known). Returns how long the
        swing foot's landing takes [s] (0 in double support or when there is no walk to stop)."""
        if not self._walking or self._tick == 0:
            return 0.0
        self._pending_goal = self._pending_velocity = None
        a = self._arrays
        j = self._tick - 1 - self._origin  # the sample handed out last: where the plan is now
        if j >= 0:
            self._rest_from = (a["p"][:, j].copy(), a["R"][:, j].copy(), int(a["support"][j]),
                               self._footsteps[min(int(a["index"][j]), len(self._footsteps) - 1)])
        p, R, support, dst = self._rest_from
        p, R = p.copy(), R.copy()  # (2, 3), (2, 3, 3)
        zmp0 = np.array([float(zmp_world_xy[0]), float(zmp_world_xy[1]), 0.0])
        zmp0[2] = 0.5 * (p[_R, 2] + p[_L, 2]) if support == _BOTH or swing_foot_loaded else p[support, 2]
        legs = ("rleg", "lleg")
        stand = support if support != _BOTH else _R
        steps = [Footstep(legs[stand], *(float(v) for v in p[stand]),
                          yaw=float(np.arctan2(R[stand, 1, 0], R[stand, 0, 0])),
                          step_time_s=self.footstep_params.step_time_s)]
        blocks = []
        landing_s = 0.0
        if support != _BOTH:
            sw = 1 - support
            if dst.leg != legs[sw]:  # (the footstep being stepped is the swing foot's) else land it level
                dst = Footstep(legs[sw], float(p[sw, 0]), float(p[sw, 1]), float(p[support, 2]))
            yaw_now = float(np.arctan2(R[sw, 1, 0], R[sw, 0, 0]))
            landing = Footstep(dst.leg, float(p[sw, 0]), float(p[sw, 1]), dst.z, yaw_now, dst.roll, dst.pitch,
                               step_time_s=self.footstep_params.step_time_s)
            height = float(p[sw, 2] - landing.z)
            n = self._n_ticks(self.dt_s * max(1, int(np.ceil(max(min_landing_time_s, abs(height) / landing_speed_m_s)
                                                            / self.dt_s))))
            s_mj = min_jerk(np.arange(1, n + 1) / n)
            landing_s = n * self.dt_s
            q_dst = _q_of(landing)
            rpy_now = np.array([float(np.arctan2(R[sw, 2, 1], R[sw, 2, 2])), float(-np.arcsin(R[sw, 2, 0])), yaw_now])
            rpy_sw = rpy_now[None] + s_mj[:, None] * (q_dst[3:] - rpy_now)[None]
            pp = np.repeat(p[:, None], n, axis=1)
            RR = np.repeat(R[:, None], n, axis=1)
            pp[sw] = p[sw][None] + s_mj[:, None] * (q_dst[:3] - p[sw])[None]
            RR[sw] = _rpy_matrices(rpy_sw)
            landing_support = _BOTH if swing_foot_loaded else support
            blocks.append({"zmp": np.repeat(zmp0[None], n, axis=0), "p": pp, "R": RR,
                           "r": np.full(n, float(support == _L)), "cop": np.zeros((n, 2)), "pitch": np.zeros((n, 2)),
                           "support": np.full(n, landing_support, dtype=np.int8),
                           "index": np.full(n, 1, dtype=np.int32)})
            p[sw], R[sw] = q_dst[:3], _rpy_matrices(q_dst[None, 3:])[0]
            steps.append(landing)
        n = self._n_ticks(REST_STOP_DOUBLE_SUPPORT_S)
        t = min_jerk(np.arange(1, n + 1) / n)[:, None]
        mid = 0.5 * (p[_R] + R[_R] @ self._zmp_offsets[_R] + p[_L] + R[_L] @ self._zmp_offsets[_L])
        blocks.append({"zmp": zmp0[None] + t * (mid - zmp0)[None], "p": np.repeat(p[:, None], n, axis=1),
                       "R": np.repeat(R[:, None], n, axis=1), "r": np.full(n, 0.5), "cop": np.zeros((n, 2)),
                       "pitch": np.zeros((n, 2)), "support": np.full(n, _BOTH, dtype=np.int8),
                       "index": np.full(n, len(steps), dtype=np.int32)})
        new = {key: np.concatenate([b[key] for b in blocks], axis=1 if key in ("p", "R") else 0) for key in blocks[0]}
        self._arrays = {key: read_only(v) for key, v in new.items()}
        self._origin = self._tick
        self._end_tick = self._tick + len(new["zmp"])
        start = self._tick
        self._segments = []
        for k, b in enumerate(blocks):
            kind = "end" if k == len(blocks) - 1 else "step"
            index = int(b["index"][0])
            seg = _Segment(kind, index, len(b["zmp"]) * self.dt_s, len(b["zmp"]), start, np.stack(
                [np.concatenate([b["p"][f, 0], [0.0, 0.0, 0.0]]) for f in (_R, _L)]))
            self._segments.append(seg)
            start += len(b["zmp"])
        self._footsteps = steps
        self._plan_version += 1
        self._stepper = None
        self._checks = {}
        self._stopping_from_rest = True
        return landing_s

    def replan(self, footsteps: Sequence[Footstep], from_index: int) -> None:
        """Replace the plan from footstep `from_index` on (>= the overwritable index) and resample from there."""
        if not self._walking:
            raise InvalidState("replan needs a walk in progress; use plan() to start one")
        if self._stopping_from_rest:
            raise InvalidState("the walk is ending (a stop from rest after the e-stop); wait for it to end")
        k = self._overwritable_index()
        if from_index < k:
            raise InvalidCommand(f"from_index={from_index}; footsteps before the overwritable index {k} "
                                 "are being stepped on")
        footsteps = list(footsteps)
        if footsteps[:from_index] != self._footsteps[:from_index]:
            raise InvalidCommand(f"replan may only change footsteps from index {from_index} on")
        self._footsteps = footsteps
        self._plan_version += 1
        self._resample_from(from_index - 1)

    def move_footsteps(self, xy_by_index: dict[int, tuple[float, float]], landed: bool = False,
                       zmp_world: np.ndarray | None = None) -> None:
        """Move footsteps {index: (x, y) [m]} (world; heights and orientations kept) while the plan is walked: the
        emergency step re-plans its landings from the measured capture point.

        A footstep not stepped yet is replaced. The footstep being stepped on: the rest of its swing bends toward
        the new landing by a min-jerk blend from the pose planned for the next tick (no jump); `landed`: its foot
        has touched the ground there already (earlier than planned), so it stays there and the rest of the step is
        double support. The reference ZMP of the rest of that step is recomputed from the new foot poses (flat
        soles, no toe-heel offsets); the later segments are resampled once.

        `zmp_world`: the reference ZMP of the next ticks, as set_zmp takes it, set with the move (the emergency
        step's, planned from the capture point); the feet's is then not computed where it replaces it."""
        if not self._walking or self._stopping_from_rest:
            raise InvalidState("move_footsteps needs a footstep plan being walked")
        seg_i = self._segments.index(self._current_segment())
        seg = self._segments[seg_i]
        for index in xy_by_index:
            if not seg.index <= index < len(self._footsteps) or (index == seg.index and seg.kind != "step"):
                raise InvalidCommand(f"move_footsteps({index}): only the footstep being stepped on ({seg.index}, "
                                     f"{seg.kind}) or a later one (< {len(self._footsteps)}) may move")
        if landed and seg.index not in xy_by_index:
            raise InvalidState(f"move_footsteps(landed=True) must move the footstep being stepped on ({seg.index})")
        if zmp_world is not None and not landed:
            patch = self._swing_patch(seg_i, xy_by_index, zmp_world)
            if patch is not None:
                self.apply(patch)
                return
        for index, (x_m, y_m) in xy_by_index.items():
            fs = self._footsteps[index]
            if index == seg.index:
                self._bend_swing(seg, fs, float(x_m), float(y_m), landed)
            self._footsteps[index] = fs.replaced(x=float(x_m), y=float(y_m))
        self._plan_version += 1
        self._resample_from(seg_i, keep_first=True)
        if zmp_world is not None:
            self.set_zmp(zmp_world)

    def prepare_move_swing(self, xy_by_index: dict[int, tuple[float, float]],
                           zmp_world: np.ndarray) -> GaitPatch | None:
        """move_footsteps(xy_by_index, zmp_world=zmp_world) computed ahead, the plan unchanged: its patch when it
        takes the swing-only path (_swing_patch), else None (the call itself then does it, or says what is wrong)."""
        if not self._walking or self._stopping_from_rest:
            return None
        seg_i = self._segments.index(self._current_segment())
        seg = self._segments[seg_i]
        if any(not seg.index <= i < len(self._footsteps) or (i == seg.index and seg.kind != "step")
               for i in xy_by_index):
            return None
        return self._swing_patch(seg_i, xy_by_index, zmp_world)

    def _swing_patch(self, seg_i: int, xy_by_index: dict[int, tuple[float, float]],
                     zmp_world: np.ndarray) -> GaitPatch | None:
        """move_footsteps of the footstep in the air when only the final double support follows it and the ZMP
        given replaces all of the feet's: the swing bends and the swing foot's position in the final double support
        moves, nothing else changes (what resampling gives, without it: the emergency step moves its landing
        every tick). None (nothing to patch this way) in any other case."""
        seg = self._segments[seg_i]
        rest = self._segments[seg_i + 1:]
        j0 = self._tick - self._origin
        if (seg.kind != "step" or list(xy_by_index) != [seg.index] or len(rest) != 1 or rest[0].kind != "end"
                or len(zmp_world) < len(self._arrays["zmp"]) - j0):
            return None
        end = rest[0]
        fs = self._footsteps[seg.index]
        x_m, y_m = (float(v) for v in xy_by_index[seg.index])
        sw = _L if fs.leg == "lleg" else _R
        a = self._arrays
        base = seg.start_tick - self._origin
        j1 = base + seg.n_ticks
        p, zmp = a["p"].copy(), a["zmp"].copy()
        w = self._swing_blend(seg, j0)
        p[sw, j0:j1, 0] += w * (x_m - fs.x)
        p[sw, j0:j1, 1] += w * (y_m - fs.y)
        e0 = end.start_tick - self._origin
        p[sw, e0:e0 + end.n_ticks, :2] = (x_m, y_m)  # the final double support: the feet where the step ends
        zmp[j0:] = np.asarray(zmp_world, dtype=float)[:len(zmp) - j0]
        q_end = seg.q_end.copy()
        q_end[sw, :2] = (x_m, y_m)
        return GaitPatch(self._source(), {**a, "p": read_only(p), "zmp": read_only(zmp)},
                         (seg_i, fs.replaced(x=x_m, y=y_m), q_end, q_end.copy()))

    def prepare_set_zmp(self, zmp_world: np.ndarray) -> GaitPatch:
        """set_zmp(zmp_world) computed ahead, the plan unchanged (see there)."""
        if not self._walking:
            raise InvalidState("set_zmp needs a walk in progress")
        zmp = self._arrays["zmp"].copy()
        j0 = self._tick - self._origin
        m = min(len(zmp_world), len(zmp) - j0)
        zmp[j0:j0 + m] = np.asarray(zmp_world, dtype=float)[:m]
        return GaitPatch(self._source(), {**self._arrays, "zmp": read_only(zmp)})

    def _source(self) -> tuple:
        return (self._arrays, self._tick, self._plan_version, self.params, self._plan_params, self._walking,
                self._stopping_from_rest)

    def apply(self, patch: GaitPatch) -> bool:
        """Put in a patch computed ahead; False (nothing done) when the plan is no longer the one it was computed
        from (a tick, a new plan or re-plan, a ZMP set, new parameters, the walk ended), the caller then redoes it."""
        arrays, tick, version, params, plan_params, walking, stopping = patch.source
        if not (self._arrays is arrays and self._tick == tick and self._plan_version == version
                and self.params is params and self._plan_params is plan_params and self._walking == walking
                and self._stopping_from_rest == stopping):
            return False
        self._arrays = patch.arrays
        if patch.landing is not None:
            seg_i, fs, q_end, q_end_copy = patch.landing
            seg, end = self._segments[seg_i], self._segments[seg_i + 1]
            seg.q_end = q_end
            end.q_start, end.q_end = q_end, q_end_copy
            self._footsteps[seg.index] = fs
            self._plan_version += 1
        return True

    def _swing_blend(self, seg: _Segment, j0: int) -> np.ndarray:
        """The min-jerk blend [-] toward a moved landing of the segment's samples from j0 (array row) on: local rows
        0 .. n_land - 1 swing (t < ta), the blend reaching 1 on the last of them."""
        gp = seg.params or self.params
        base = seg.start_tick - self._origin
        n_land = int(np.ceil((1.0 - gp.double_support_ratio_after) * seg.n_ticks - 1e-9)) - 1
        i = np.arange(j0, base + seg.n_ticks) - base
        i0 = j0 - base
        return np.where(i >= n_land - 1, 1.0, min_jerk((i - i0 + 1) / max(n_land - i0, 1)))

    def _bend_swing(self, seg: _Segment, fs: Footstep, x_m: float, y_m: float, landed: bool) -> None:
        """move_footsteps' patch of the rest of the segment being stepped (see there)."""
        sw = _L if fs.leg == "lleg" else _R
        a = self._arrays
        j0 = self._tick - self._origin  # the next sample handed out
        base = seg.start_tick - self._origin  # the segment's first sample
        j1 = base + seg.n_ticks
        p, R, support, zmp = a["p"].copy(), a["R"].copy(), a["support"].copy(), a["zmp"].copy()
        if landed:
            q_dst = _q_of(fs)
            p[sw, j0:j1] = (x_m, y_m, q_dst[2])
            R[sw, j0:j1] = _rpy_matrices(q_dst[None, 3:])[0]
            support[j0:j1] = _BOTH
        else:
            w = self._swing_blend(seg, j0)
            p[sw, j0:j1, 0] += w * (x_m - fs.x)
            p[sw, j0:j1, 1] += w * (y_m - fs.y)
        r = a["r"][j0:j1]
        cop = np.einsum("fnij,fj->fni", R[:, j0:j1], self._zmp_offsets)  # (2, n, 3) flat soles
        zmp[j0:j1] = (1.0 - r)[:, None] * (p[_R, j0:j1] + cop[_R]) + r[:, None] * (p[_L, j0:j1] + cop[_L])
        self._arrays = {**a, "p": read_only(p), "R": read_only(R), "support": read_only(support),
                        "zmp": read_only(zmp)}
        seg.q_end = seg.q_end.copy()
        seg.q_end[sw, :2] = (x_m, y_m)

    def set_zmp(self, zmp_world: np.ndarray) -> None:
        """Overwrite the reference ZMP of the next ticks with `zmp_world` (m, 3) [m], row 0 for the next tick
        (the emergency step plans it from the measured capture point); rows past the plan's end are dropped,
        the plan's own ZMP stays after the m given."""
        self.apply(self.prepare_set_zmp(zmp_world))

    # ----- per tick -------------------------------------------------------------------------------------

    def tick(self) -> GaitSample:
        """The plan at the next tick (the idle pose when not walking). O(1): slices precomputed samples
        (except the tick that starts a goPos left waiting for the end of the previous walk)."""
        if not self._walking:
            if self._pending_velocity is not None:
                velocity, self._pending_velocity = self._pending_velocity, None
                self.go_velocity(*velocity)
            elif self._pending_goal is None:
                return self._idle
            else:
                self._start_pending_goal()
        if self._tick in self._checks:
            self._velocity_check(self._checks[self._tick])
        j = self._tick - self._origin
        a = self._arrays
        sample = GaitSample(
            time_s=(self._tick + 1) * self.dt_s,
            walking=True,
            support=_SUPPORT_NAMES[a["support"][j]],
            footstep_index=int(a["index"][j]),
            remaining_footsteps=len(self._footsteps) - max(int(a["index"][j]), 1),
            zmp_world=a["zmp"][j],
            p_rfoot_world=a["p"][_R, j],
            R_rfoot_world=a["R"][_R, j],
            p_lfoot_world=a["p"][_L, j],
            R_lfoot_world=a["R"][_L, j],
            r_lleg=float(a["r"][j]),
            cop_offset_x_m=a["cop"][j],
            pitch_offset_rad=a["pitch"][j],
        )
        self._tick += 1
        if self._tick >= self._end_tick:
            self._finish()
        return sample

    def zmp_preview(self, n: int | None = None) -> np.ndarray:
        """(n, 3) reference ZMPs [m] of the next n ticks; row 0 is what the next `tick()` returns.

        Defaults to n = round(preview_time_s / dt_s); past the end of the plan the last ZMP is repeated.
        """
        if n is None:
            n = int(round(self.params.preview_time_s / self.dt_s))
        if not self._walking:
            return np.broadcast_to(self._idle.zmp_world, (n, 3))
        j = self._tick - self._origin
        zmp = self._arrays["zmp"]
        if j + n <= len(zmp):
            return zmp[j:j + n]
        out = np.empty((n, 3))
        m = len(zmp) - j
        out[:m] = zmp[j:]
        out[m:] = zmp[-1]
        return out

    # ----- internals ------------------------------------------------------------------------------------

    def _n_ticks(self, duration_s: float) -> int:
        n = int(round(duration_s / self.dt_s))
        if n < 1 or abs(n * self.dt_s - duration_s) > 1e-9:
            raise InvalidCommand(f"step time {duration_s} s is not a whole number of ticks of {self.dt_s} s; "
                                 f"use e.g. {max(n, 1) * self.dt_s:.6g} s")
        return n

    def _current_segment(self) -> _Segment:
        t = min(self._tick, self._end_tick - 1)
        for seg in reversed(self._segments):
            if seg.start_tick <= t:
                return seg
        return self._segments[0]

    def _overwritable_index(self) -> int:
        return self._current_segment().index + 1

    def _free_index(self) -> int:
        """The first footstep a goPos while walking may replace: the overwritable one before the current
        segment's mid-step check, the one after it from the check on (hrpsys go_pos_param_2_footstep_nodes_list)."""
        seg = self._current_segment()
        check = seg.start_tick + seg.n_ticks // 2 - 1
        return seg.index + (1 if self._tick < check else 2)

    def _start_pending_goal(self) -> None:
        """Plan the goPos that waited for the walk's end: to its goal mid-coords from the feet as they stand."""
        goal, self._pending_goal = self._pending_goal, None
        start = mid_coords(self._feet["rleg"], self._feet["lleg"])
        dx, dy, dth = _relative_planar(start, goal)
        origin = self._walk_origin
        self.go_pos(dx, dy, dth)
        self._walk_origin = origin  # still the same walk as far as the next goPos is concerned

    def _velocity_check(self, segment_index: int) -> None:
        """hrpsys mid-step overwrite check: the velocity steps after the next footstep are recomputed."""
        stepper = self._stepper
        if stepper is None or stepper.state != "walking":
            return
        stepper.advance_to(segment_index)
        self.replan(stepper.replan(), segment_index + 1)

    def _idle_sample(self) -> GaitSample:
        rf, lf = self._feet["rleg"], self._feet["lleg"]
        R_r, R_l = rf.T_world_foot[:3, :3], lf.T_world_foot[:3, :3]
        zmp = 0.5 * (rf.position + R_r @ self._zmp_offsets[_R] + lf.position + R_l @ self._zmp_offsets[_L])
        return GaitSample(0.0, False, "both", 0, 0, read_only(zmp), read_only(rf.position), read_only(R_r),
                          read_only(lf.position), read_only(R_l), 0.5, read_only(np.zeros(2)),
                          read_only(np.zeros(2)))

    def abort(self) -> str:
        """End the walk at the sample handed out last: the feet stay where the plan has them now, a swing foot in
        the air included (the caller's next plan must land it: the capture step while walking). Returns the
        support of that sample ('rleg', 'lleg' or 'both'); 'both' when not walking."""
        if not self._walking:
            return "both"
        j = max(self._tick - 1 - self._origin, 0)
        support = _SUPPORT_NAMES[int(self._arrays["support"][j])]
        self._pending_goal = self._pending_velocity = None
        self._stopping_from_rest = False
        self._finish(j)
        return support

    def _finish(self, j: int | None = None) -> None:
        a = self._arrays
        j = self._end_tick - 1 - self._origin if j is None else j
        for leg, f in (("rleg", _R), ("lleg", _L)):
            T = np.eye(4)
            T[:3, :3] = a["R"][f, j]
            T[:3, 3] = a["p"][f, j]
            self._feet[leg] = Footstep.from_T(leg, T)
        self._walking = False
        if self._stepper is not None:
            self._stepper.state = "idle"
        self._idle = self._idle_sample()

    def _weight(self, k: int) -> float:
        """Eq. 4 weight of the left foot while footstep k is stepped on (support = the other leg)."""
        return 1.0 if other_leg(self._footsteps[k].leg) == "lleg" else 0.0

    def _resample_from(self, seg_index: int, keep_first: bool = False) -> None:
        """Rebuild segments seg_index.. (and the end segment) and their samples; keep what comes before.
        `keep_first`: segment seg_index keeps its samples (patched by the caller), the later ones are rebuilt."""
        seg_index = max(seg_index, 0)
        segs = self._segments[: seg_index + 1]
        n_steps = len(self._footsteps)
        gp = self._plan_params or self.params
        for k in range(seg_index + 1, n_steps + 1):
            prev = segs[-1]
            duration = self._footsteps[k].step_time_s if k < n_steps else gp.final_double_support_s
            segs.append(_Segment("step" if k < n_steps else "end", k, duration, self._n_ticks(duration),
                                 prev.start_tick + prev.n_ticks, None, params=gp))
        self._segments = segs
        blocks = []
        first = seg_index + 1 if keep_first else seg_index
        for k in range(first, len(segs)):
            if k > 0:
                segs[k].q_start = segs[k - 1].q_end
            blocks.append(self._sample_segment(segs[k]))
        keep_from = self._current_segment().start_tick if self._arrays is not None else 0
        new = {key: np.concatenate([b[key] for b in blocks], axis=1 if key in ("p", "R") else 0)
               for key in blocks[0]}
        if self._arrays is not None:
            lo, hi = keep_from - self._origin, segs[first].start_tick - self._origin
            new = {key: np.concatenate([self._arrays[key][:, lo:hi] if key in ("p", "R") else self._arrays[key][lo:hi],
                                        new[key]], axis=1 if key in ("p", "R") else 0) for key in new}
        self._origin = keep_from
        self._arrays = {key: read_only(v) for key, v in new.items()}
        self._end_tick = segs[-1].start_tick + segs[-1].n_ticks
        self._checks = {}
        if self._stepper is not None:
            for seg in segs[:-1]:
                self._checks[seg.start_tick + seg.n_ticks // 2 - 1] = seg.index

    def _sample_segment(self, seg: _Segment) -> dict[str, np.ndarray]:
        """Vectorised samples of one segment at local times dt, 2 dt, ..., duration (the last one exact)."""
        n, T = seg.n_ticks, seg.duration_s
        t = np.arange(1, n + 1) * self.dt_s
        t[-1] = T
        q = seg.q_start.copy()  # (2, 6)
        p = np.repeat(q[:, None, :3], n, axis=1)  # (2, n, 3)
        R = np.repeat(_rpy_matrices(q[:, 3:])[:, None], n, axis=1)  # (2, n, 3, 3)
        cop = np.zeros((n, 2))
        pitch = np.zeros((n, 2))
        support = np.full(n, _BOTH, dtype=np.int8)
        R_flat = R.copy()  # sole orientation without the toe-heel pitch (COP frame)
        p_flat = p.copy()
        steps, k = self._footsteps, seg.index
        gp = seg.params or self.params
        ds_b, ds_a = gp.double_support_ratio_before, gp.double_support_ratio_after
        if seg.kind == "start":
            w = self._weight(1) if len(steps) > 1 else 0.5
            r = 0.5 + (w - 0.5) * t / T
        elif seg.kind == "end":
            r_start = self._weight(k - 1) if k > 1 else 0.5
            r = r_start + (0.5 - r_start) * t / T
        else:
            fs = steps[k]
            sw = _L if fs.leg == "lleg" else _R
            w = self._weight(k)
            r_start = 0.5 * (self._weight(k - 1) + w) if k > 1 else w
            r_end = 0.5 * (w + self._weight(k + 1)) if k + 1 < len(steps) else w
            tb, ta = ds_b * T, T - ds_a * T
            r = np.full(n, w)
            if tb > 0.0:
                r = np.where(t < tb, r_start + (w - r_start) * t / tb, r)
            if ta < T:
                r = np.where(t > ta, w + (r_end - w) * (t - ta) / (T - ta), r)
            support[(t > tb) & (t < ta)] = 1 - sw
            q_dst = _q_of(fs)
            s = np.clip((t - tb) / max(ta - tb, 1e-12), 0.0, 1.0)
            p_sw = swing_position(s, q[sw, :3], q_dst[:3], fs.step_height_m, gp.orbit_type)
            rpy_sw = swing_rpy(s, q[sw, 3:], q_dst[3:])
            R_sw = _rpy_matrices(rpy_sw)
            p_flat[sw], R_flat[sw] = p_sw, R_sw
            th = self.toe_heel
            backward = float((R[sw, 0].T @ (q_dst[:3] - q[sw, :3]))[0]) < -1e-6
            if th.use_cop_transition:
                cop[:, sw] = cop_offset_x(t, T, th, backward)
            if fs.toe_angle_rad > 0.0 or fs.heel_angle_rad > 0.0:
                theta = foot_pitch_offset(t, T, fs.toe_angle_rad, fs.heel_angle_rad, th, backward)
                pitch[:, sw] = theta
                R_pitched = R_sw @ _ry(theta)
                pivot = np.zeros((n, 3))
                pivot[:, 0] = np.where(theta > 0.0, th.toe_offset_x_m, th.heel_offset_x_m)
                p_sw = p_sw + np.einsum("nij,nj->ni", R_sw - R_pitched, pivot)
                R_sw = R_pitched
            p[sw], R[sw] = p_sw, R_sw
            q[sw] = q_dst
        cop_local = np.repeat(self._zmp_offsets[None], n, axis=0)  # (n, 2, 3)
        cop_local[:, :, 0] += cop
        p_cop = p_flat + np.einsum("fnij,nfj->fni", R_flat, cop_local)  # (2, n, 3)
        zmp = (1.0 - r)[:, None] * p_cop[_R] + r[:, None] * p_cop[_L]
        seg.q_end = q
        return {"zmp": zmp, "p": p, "R": R, "r": r, "cop": cop, "pitch": pitch, "support": support,
                "index": np.full(n, k, dtype=np.int32)}
