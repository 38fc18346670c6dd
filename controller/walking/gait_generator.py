"""Walking plan sampled per tick: reference ZMP (Eq. 4, toe-heel), both foot poses, support state, ZMP preview."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.types import read_only
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
    stop_after,
    stop_in_place,
)
from controller.walking.gait_edits import GaitEdits, GaitPatch
from controller.walking.gait_sampling import (
    BOTH,
    LEFT,
    RIGHT,
    SUPPORT_NAMES,
    GaitParams,
    Segment,
    compose_planar,
    n_ticks,
    q_of,
    relative_planar,
    rest_stop,
    sample_segment,
    zmp_offsets,
)
from controller.walking.toe_heel import ToeHeelParams

__all__ = ["GaitGenerator", "GaitParams", "GaitPatch", "GaitSample"]


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



class GaitGenerator(GaitEdits):
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
        self._zmp_offsets = zmp_offsets(p)  # (2, 3) [m]
        self._footsteps: list[Footstep] = []
        self._segments: list[Segment] = []
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
        self._idle_preview: tuple | None = None  # (idle ZMP, n, its broadcast view): zmp_preview while standing
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
        if not 0 <= j < len(support) or support[j] == BOTH:
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
        self._zmp_offsets = zmp_offsets(params or self.params)  # a plan's own COPs (the closing step's) while it lasts
        self._walk_origin = mid_coords(self._feet["rleg"], self._feet["lleg"])
        q0 = np.stack([q_of(self._feet["rleg"]), q_of(self._feet["lleg"])])
        self._segments = [Segment("start", 0, first.step_time_s, self._n_ticks(first.step_time_s), 0, q0,
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
        goal = compose_planar(self._walk_origin, (dx_m, dy_m, dtheta_rad))
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
            self._zmp_offsets = zmp_offsets(params)
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
        (a goPos waiting for the end of the walk is dropped). In a goPos or footstep walk too, where hrpsys walks
        on to the end (soak seed 10139: "stopping", and a 41-step walk went on for 20 s); not in a plan with its
        own timing (a catching step, the closing step), which ends standing anyway."""
        self._pending_goal = self._pending_velocity = None
        if self._walking and self._stepper is None and self._plan_params is None and not self._stopping_from_rest:
            k = self._free_index()
            if k < len(self._footsteps):
                self.replan(stop_after(self._footsteps[:k], self.footstep_params, self.stride_limits), k)
            return
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
        q_other = self._segments[k - 1].q_start[LEFT if landed.leg == "rleg" else RIGHT]
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
        steps, blocks, landing_s = rest_stop(self._rest_from, zmp_world_xy, swing_foot_loaded, landing_speed_m_s,
                                             min_landing_time_s, self.footstep_params.step_time_s, self._zmp_offsets,
                                             self.dt_s)
        new = {key: np.concatenate([b[key] for b in blocks], axis=1 if key in ("p", "R") else 0) for key in blocks[0]}
        self._arrays = {key: read_only(v) for key, v in new.items()}
        self._origin = self._tick
        self._end_tick = self._tick + len(new["zmp"])
        start = self._tick
        self._segments = []
        for k, b in enumerate(blocks):
            kind = "end" if k == len(blocks) - 1 else "step"
            index = int(b["index"][0])
            seg = Segment(kind, index, len(b["zmp"]) * self.dt_s, len(b["zmp"]), start, np.stack(
                [np.concatenate([b["p"][f, 0], [0.0, 0.0, 0.0]]) for f in (RIGHT, LEFT)]))
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
            support=SUPPORT_NAMES[a["support"][j]],
            footstep_index=int(a["index"][j]),
            remaining_footsteps=len(self._footsteps) - max(int(a["index"][j]), 1),
            zmp_world=a["zmp"][j],
            p_rfoot_world=a["p"][RIGHT, j],
            R_rfoot_world=a["R"][RIGHT, j],
            p_lfoot_world=a["p"][LEFT, j],
            R_lfoot_world=a["R"][LEFT, j],
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
        if not self._walking:  # the idle ZMP repeated: one broadcast view per idle sample (np.broadcast_to costs ~4 us)
            zmp_idle = self._idle.zmp_world
            cached = self._idle_preview
            if cached is None or cached[0] is not zmp_idle or cached[1] != n:
                cached = self._idle_preview = (zmp_idle, n, np.broadcast_to(zmp_idle, (n, 3)))
            return cached[2]
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
        return n_ticks(duration_s, self.dt_s)


    def _current_segment(self) -> Segment:
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
        dx, dy, dth = relative_planar(start, goal)
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
        zmp = 0.5 * (rf.position + R_r @ self._zmp_offsets[RIGHT] + lf.position + R_l @ self._zmp_offsets[LEFT])
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
        support = SUPPORT_NAMES[int(self._arrays["support"][j])]
        self._pending_goal = self._pending_velocity = None
        self._stopping_from_rest = False
        self._finish(j)
        return support

    def _finish(self, j: int | None = None) -> None:
        a = self._arrays
        j = self._end_tick - 1 - self._origin if j is None else j
        for leg, f in (("rleg", RIGHT), ("lleg", LEFT)):
            T = np.eye(4)
            T[:3, :3] = a["R"][f, j]
            T[:3, 3] = a["p"][f, j]
            self._feet[leg] = Footstep.from_T(leg, T)
        self._walking = False
        if self._stepper is not None:
            self._stepper.state = "idle"
        self._idle = self._idle_sample()

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
            segs.append(Segment("step" if k < n_steps else "end", k, duration, self._n_ticks(duration),
                                 prev.start_tick + prev.n_ticks, None, params=gp))
        self._segments = segs
        blocks = []
        first = seg_index + 1 if keep_first else seg_index
        for k in range(first, len(segs)):
            if k > 0:
                segs[k].q_start = segs[k - 1].q_end
            blocks.append(sample_segment(segs[k], self._footsteps, self.params, self.toe_heel, self._zmp_offsets,
                                         self.dt_s))
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
