"""SequencePlayer layer (paper Sec. III-A, hrpsys SequencePlayer): plays operator and planner commands as
Hoff-Arbib minimum-jerk motions of the joints, base pose, ZMP and wrenches; the source of the reference."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.layer import Layer, Params, Status, described
from controller.core.types import Reference, TickContext
from controller.interpolation.hoff_arbib import HoffArbibTrack
from robot.names import FORCE_SENSOR_NAMES, JOINT_GROUPS, JOINT_NAMES, NUM_JOINTS

#: ik_solver(group, q_current_rad (30,), base_pos_world (3,), base_rpy_rad (3,), target_pos (3,) [m],
#:           target_rpy (3,) [rad], frame or None) -> q_rad (30,); frame None means world coordinates.
IkSolver = Callable[[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, "str | None"],
                    np.ndarray]

NUM_WRENCH_VALUES = 6 * len(FORCE_SENSOR_NAMES)


#: the Reference fields the channels interpolate, in the order of SequencePlayer._channels
_CHANNEL_FIELDS = ("q_rad", "base_pos_world", "base_rpy_rad", "zmp_base", "wrenches")


@dataclass(frozen=True)
class SequencePlayerParams(Params):
    # hrpsys interpolator default_avg_vel: sets the duration of a joint command given with time_s=None
    default_avg_vel_rad_s: float = field(default=0.5, metadata={"unit": "rad/s", "min": 0.01, "max": 10.0})
    # hrpsys calc_interpolation_time floor for those automatic durations
    min_auto_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.01, "max": 60.0})


@dataclass(frozen=True, slots=True)
class SequencePlayerStatus(Status):
    interpolating: bool = field(metadata=described("a motion is being interpolated (isInterpolating)"))
    active_groups: tuple[str, ...] = field(metadata=described("joint groups moving now"))
    remaining_s: float = field(metadata=described("time left of the longest motion", "s"))


class _Channel:
    """One interpolated vector (n,) whose dimensions are moved by tracks over disjoint index sets."""

    def __init__(self, x0: np.ndarray) -> None:
        x0 = np.asarray(x0, dtype=float).reshape(-1)
        self.xva = np.zeros((3, x0.size))  # rows: x, v, a
        self.xva[0] = x0
        self.all = np.arange(x0.size)
        # (indices, track); a track over every dimension is stored with slice(None) (faster writes)
        self.motions: list[tuple[np.ndarray, slice | np.ndarray, HoffArbibTrack]] = []

    @property
    def x(self) -> np.ndarray:
        return self.xva[0]

    def play(self, idx: np.ndarray, goals: np.ndarray, durations_s: Sequence[float]) -> None:
        """Replace the motion of dimensions `idx` by a sequence, from their current (x, v, a)."""
        track = HoffArbibTrack(*self.xva[:, idx])
        track.go_sequence(goals, durations_s)
        self._commit(idx, track)

    def brake(self, idx: np.ndarray, duration_s: float) -> None:
        """Replace the motion of dimensions `idx` by a minimum-jerk stop in `duration_s`."""
        track = HoffArbibTrack(*self.xva[:, idx])
        track.brake(duration_s)
        self._commit(idx, track)

    def freeze(self, idx: np.ndarray) -> None:
        """Stop dimensions `idx` where they are (zero velocity and acceleration)."""
        self._release(idx)
        self.xva[1:, idx] = 0.0

    def reseed(self, x0: np.ndarray) -> None:
        self.motions = []
        self.xva[:] = 0.0
        self.xva[0] = np.asarray(x0, dtype=float).reshape(-1)

    def _commit(self, idx: np.ndarray, track: HoffArbibTrack) -> None:
        self._release(idx)
        where = slice(None) if idx.size == self.all.size else idx
        self.motions.append((idx, where, track))

    def _release(self, idx: np.ndarray) -> None:
        kept = []
        for m_idx, where, track in self.motions:
            keep = ~np.isin(m_idx, idx)
            if keep.all():
                kept.append((m_idx, where, track))
            elif keep.any():
                kept.append((m_idx[keep], m_idx[keep], track.take(keep)))
        self.motions = kept

    def step(self, dt_s: float) -> None:
        finished = False
        xva = self.xva
        for _, where, track in self.motions:
            xva[:, where] = track.step_xva(dt_s)
            finished |= not track.is_moving
        if finished:
            self.motions = [m for m in self.motions if m[2].is_moving]

    def moving(self, idx: np.ndarray) -> bool:
        wanted = set(np.asarray(idx).tolist())  # plain sets: status() asks this per group every tick
        return any(not wanted.isdisjoint(m_idx.tolist()) for m_idx, _, _ in self.motions)

    def remaining_s(self) -> float:
        return max((track.remaining_s for _, _, track in self.motions), default=0.0)


class SequencePlayer(Layer):
    """The planned stream: Hoff-Arbib interpolation of joints (30), base position (3), base rpy (3),
    ZMP in the base frame (3) and wrenches (4 x 6), driven by hrpsys SequencePlayerService operations.

    Commands replace the remaining motion of the dimensions they name, starting from the current
    (x, v, a), so the stream stays velocity- and acceleration-continuous; other joints keep their motion.
    Invalid arguments raise InvalidCommand and change nothing. Joint limits are the SoftErrorLimiter's job.
    """

    name = "seq"
    description = "SequencePlayer: Hoff-Arbib interpolation of joints, base pose, ZMP and wrenches"

    def __init__(self, initial: Reference, dt_s: float, ik_solver: IkSolver | None = None,
                 params: SequencePlayerParams | None = None) -> None:
        super().__init__()
        if not (np.isfinite(dt_s) and dt_s > 0.0):
            raise InvalidCommand(f"SequencePlayer dt_s must be a finite number > 0 [s], got {dt_s!r}")
        self.dt_s = float(dt_s)
        self.params = params or SequencePlayerParams()
        self.ik_solver = ik_solver
        self.groups: dict[str, np.ndarray] = {g: np.array(idx, dtype=int) for g, idx in JOINT_GROUPS.items()}
        self._q = _Channel(initial.q_rad)
        self._base_pos = _Channel(initial.base_pos_world)
        self._base_rpy = _Channel(initial.base_rpy_rad)
        self._zmp = _Channel(initial.zmp_base)
        self._wrenches = _Channel(np.asarray(initial.wrenches).reshape(-1))
        self._channels = (self._q, self._base_pos, self._base_rpy, self._zmp, self._wrenches)  # _CHANNEL_FIELDS
        self.last_output: Reference = self._output()

    def set_params(self, params: SequencePlayerParams) -> None:
        self.params = params

    # ---- the tick -------------------------------------------------------------------------------

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        if not self.enabled:
            return ref
        if ctx.hold and self.is_interpolating():
            self.clear()  # the hard e-stop: the motion stops where it is and does not resume on release
        if not self.is_interpolating():
            ctx.ports.planned_q_rad = self.last_output.q_rad
            return self.last_output
        dt_s = ctx.dt_s
        last = self.last_output
        changes = {}
        for name, ch in zip(_CHANNEL_FIELDS, self._channels, strict=True):
            if ch.motions:
                ch.step(dt_s)
                changes[name] = ch.x.reshape(getattr(last, name).shape)  # copied and frozen by with_
        self.last_output = last.with_(**changes)
        ctx.ports.planned_q_rad = self.last_output.q_rad
        return self.last_output

    def _output(self) -> Reference:
        return Reference.from_arrays(self._q.x, base_pos_world=self._base_pos.x, base_rpy_rad=self._base_rpy.x,
                                     zmp_base=self._zmp.x,
                                     wrenches=self._wrenches.x.reshape(len(FORCE_SENSOR_NAMES), 6))

    # ---- joint angles ---------------------------------------------------------------------------

    def set_joint_angles(self, q_rad, time_s: float | None) -> None:
        """Move every joint to `q_rad` (30,) in `time_s` [s] (None: hrpsys automatic duration)."""
        q = _vector("set_joint_angles", "q_rad", q_rad, NUM_JOINTS, "one per joint, JOINT_NAMES order")
        self._play_joints("set_joint_angles", self._q.all, q[None], [time_s])

    def set_joint_angle(self, name: str, angle_rad: float, time_s: float | None) -> None:
        """Move joint `name` to `angle_rad` in `time_s` [s]; the other joints keep their motion."""
        idx = np.array([_joint_index("set_joint_angle", name)])
        q = _vector("set_joint_angle", "angle_rad", [angle_rad], 1, "one angle [rad]")
        self._play_joints("set_joint_angle", idx, q[None], [time_s])

    def set_joint_angles_sequence(self, q_seq_rad, times_s) -> None:
        """Move every joint through the poses `q_seq_rad` (k x (30,)), taking `times_s[i]` [s] each."""
        goals, times = _sequence("set_joint_angles_sequence", "q_seq_rad", q_seq_rad, times_s, NUM_JOINTS)
        self._play_joints("set_joint_angles_sequence", self._q.all, goals, times)

    def set_joint_angles_of_group(self, group: str, q_group_rad, time_s: float | None) -> None:
        """Move the joints of `group` to `q_group_rad` (one per group joint) in `time_s` [s]."""
        idx = self._group("set_joint_angles_of_group", group)
        q = _vector("set_joint_angles_of_group", "q_group_rad", q_group_rad, idx.size,
                    f"one per joint of group {group!r}: {', '.join(JOINT_NAMES[i] for i in idx)}")
        self._play_joints("set_joint_angles_of_group", idx, q[None], [time_s])

    def set_joint_angles_sequence_of_group(self, group: str, q_seq_group_rad, times_s) -> None:
        """Move the joints of `group` through the poses `q_seq_group_rad`, taking `times_s[i]` [s] each."""
        idx = self._group("set_joint_angles_sequence_of_group", group)
        goals, times = _sequence("set_joint_angles_sequence_of_group", "q_seq_group_rad", q_seq_group_rad,
                                 times_s, idx.size)
        self._play_joints("set_joint_angles_sequence_of_group", idx, goals, times)

    def _play_joints(self, op: str, idx: np.ndarray, goals: np.ndarray,
                     times_s: Sequence[float | None]) -> None:
        if len(times_s) == 1 and times_s[0] is None:
            p = self.params
            delta = np.max(np.abs(goals[0] - self._q.x[idx]), initial=0.0)
            times = [max(delta / p.default_avg_vel_rad_s, p.min_auto_time_s)]
        else:
            times = [_time(op, "time_s", t) for t in times_s]
        self._q.play(idx, goals, times)

    # ---- joint groups ---------------------------------------------------------------------------

    def add_joint_group(self, name: str, joint_names: Sequence[str]) -> None:
        """Define group `name` from joint names (hrpsys addJointGroup); existing names are refused."""
        if not isinstance(name, str) or not name or ":" in name:
            raise InvalidCommand(f"add_joint_group: name must be a non-empty string without ':', "
                                 f"got {name!r}")
        if name in self.groups:
            raise InvalidCommand(f"add_joint_group: group {name!r} exists (remove it first); "
                                 f"groups: {', '.join(sorted(self.groups))}")
        if isinstance(joint_names, str) or len(joint_names) == 0:
            raise InvalidCommand(f"add_joint_group: joint_names must be a non-empty list of names from "
                                 f"{', '.join(JOINT_NAMES)}; got {joint_names!r}")
        idx = [_joint_index("add_joint_group", j) for j in joint_names]
        if len(set(idx)) != len(idx):
            raise InvalidCommand(f"add_joint_group: joint_names has duplicates: {list(joint_names)}")
        self.groups[name] = np.array(idx, dtype=int)

    def remove_joint_group(self, name: str) -> None:
        """Forget group `name`; a motion it started plays on (motions belong to joints, not names)."""
        self._group("remove_joint_group", name)
        del self.groups[name]

    # ---- base, ZMP, wrenches --------------------------------------------------------------------

    def set_base_pos(self, pos_world, time_s: float) -> None:
        """Move the BODY position to `pos_world` (3,) [m] in `time_s` [s]."""
        self._play_all("set_base_pos", self._base_pos, "pos_world", pos_world, time_s, "x, y, z [m]")

    def set_base_rpy(self, rpy_rad, time_s: float) -> None:
        """Move the BODY roll, pitch, yaw to `rpy_rad` (3,) in `time_s` [s]."""
        self._play_all("set_base_rpy", self._base_rpy, "rpy_rad", rpy_rad, time_s, "roll, pitch, yaw [rad]")

    def set_zmp(self, zmp_base, time_s: float) -> None:
        """Move the reference ZMP to `zmp_base` (3,) [m], BODY frame, in `time_s` [s]."""
        self._play_all("set_zmp", self._zmp, "zmp_base", zmp_base, time_s, "x, y, z in the BODY frame [m]")

    def set_wrenches(self, wrenches, time_s: float) -> None:
        """Move the reference wrenches to `wrenches` ((4, 6) or (24,), FORCE_SENSOR_NAMES order) [N, N m]."""
        w = np.asarray(wrenches, dtype=float)
        if w.shape == (len(FORCE_SENSOR_NAMES), 6):
            w = w.reshape(-1)
        self._play_all("set_wrenches", self._wrenches, "wrenches", w, time_s,
                       f"(4, 6) or (24,): [fx fy fz tx ty tz] per sensor {', '.join(FORCE_SENSOR_NAMES)}")

    def _play_all(self, op: str, channel: _Channel, field_name: str, values, time_s: float,
                  what: str) -> None:
        x = _vector(op, field_name, values, channel.x.size, what)
        t = _time(op, "time_s", time_s)
        channel.play(channel.all, x[None], [t])

    # ---- IK target ------------------------------------------------------------------------------

    def set_target_pose(self, group_and_frame: str, pos, rpy, time_s: float | None) -> None:
        """Move `group`'s end effector to (pos [m], rpy [rad]) in `time_s` [s] (hrpsys setTargetPose).

        `group_and_frame` is "rarm" (target in the world) or "rarm:BODY" (in that link's frame); the
        injected ik_solver turns the pose into joint angles, played like set_joint_angles_of_group.
        """
        op = "set_target_pose"
        if not isinstance(group_and_frame, str):
            raise InvalidCommand(f"{op}: name must be 'group' or 'group:frame', got {group_and_frame!r}")
        group, _, frame = group_and_frame.partition(":")
        idx = self._group(op, group)
        pos = _vector(op, "pos", pos, 3, "x, y, z [m]")
        rpy = _vector(op, "rpy", rpy, 3, "roll, pitch, yaw [rad]")
        if time_s is not None:
            _time(op, "time_s", time_s)
        if self.ik_solver is None:
            raise InvalidState(f"{op}: no ik_solver was given to the SequencePlayer")
        q = self.ik_solver(group, self._q.x.copy(), self._base_pos.x.copy(), self._base_rpy.x.copy(),
                           pos, rpy, frame or None)
        q = np.asarray(q, dtype=float)
        if q.shape != (NUM_JOINTS,) or not np.all(np.isfinite(q[idx])):
            raise InvalidCommand(f"{op}: ik_solver returned shape {q.shape} or non-finite angles; "
                                 f"expected finite ({NUM_JOINTS},)")
        self._play_joints(op, idx, q[idx][None], [time_s])

    # ---- stopping -------------------------------------------------------------------------------

    def clear(self) -> None:
        """Stop every channel where it is now (velocity and acceleration to zero)."""
        for ch in self._channels:
            ch.freeze(ch.all)

    def clear_joint_angles(self) -> None:
        """Stop every joint where it is now."""
        self._q.freeze(self._q.all)

    def clear_joint_angles_of_group(self, group: str) -> None:
        """Stop the joints of `group` where they are now."""
        self._q.freeze(self._group("clear_joint_angles_of_group", group))

    def clear_of_group(self, group: str, time_s: float = 0.0) -> None:
        """Stop `group`: time_s = 0 freezes it where it is; time_s > 0 brakes to rest (minimum jerk)."""
        idx = self._group("clear_of_group", group)
        t = _time("clear_of_group", "time_s", time_s, allow_zero=True)
        if t == 0.0:
            self._q.freeze(idx)
        else:
            self._q.brake(idx, t)

    # ---- queries --------------------------------------------------------------------------------

    def is_interpolating(self) -> bool:
        """True while any channel moves (hrpsys waitInterpolation waits for this to turn False)."""
        return any(ch.motions for ch in self._channels)

    def is_interpolating_group(self, group: str) -> bool:
        """True while any joint of `group` moves (hrpsys waitInterpolationOfGroup)."""
        return self._q.moving(self._group("is_interpolating_group", group))

    def status(self) -> SequencePlayerStatus:
        moving = [ch for ch in self._channels if ch.motions]  # a channel at rest has 0 s remaining
        active = tuple(g for g, idx in self.groups.items() if self._q.moving(idx)) if self._q.motions else ()
        return SequencePlayerStatus(enabled=self.enabled, interpolating=bool(moving),  # is_interpolating()
                                    active_groups=active,
                                    remaining_s=max((ch.remaining_s() for ch in moving), default=0.0))

    def _group(self, op: str, group: str) -> np.ndarray:
        try:
            return self.groups[group]
        except (KeyError, TypeError):
            raise InvalidCommand(f"{op}: unknown joint group {group!r}; valid groups: "
                                 f"{', '.join(sorted(self.groups))}") from None


def _joint_index(op: str, name: str) -> int:
    if isinstance(name, str) and name in JOINT_NAMES:
        return JOINT_NAMES.index(name)
    raise InvalidCommand(f"{op}: unknown joint {name!r}; valid joints: {', '.join(JOINT_NAMES)}")


def _vector(op: str, field_name: str, values, n: int, what: str) -> np.ndarray:
    try:
        x = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise InvalidCommand(f"{op}: {field_name} must be {n} numbers ({what}), got {values!r}") from None
    if x.shape != (n,):
        raise InvalidCommand(f"{op}: {field_name} must have shape ({n},) ({what}), got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        bad = np.flatnonzero(~np.isfinite(x)).tolist()
        raise InvalidCommand(f"{op}: {field_name} must be finite; non-finite at indices {bad}")
    return x


def _time(op: str, field_name: str, time_s, allow_zero: bool = False) -> float:
    try:
        t = float(time_s)
    except (TypeError, ValueError):
        t = float("nan")
    if not np.isfinite(t) or t < 0.0 or (t == 0.0 and not allow_zero):
        allowed = ">= 0 (0 freezes)" if allow_zero else "> 0"
        raise InvalidCommand(f"{op}: {field_name} must be a finite number {allowed} [s], got {time_s!r}")
    return t


def _sequence(op: str, field_name: str, seq, times_s, n: int) -> tuple[np.ndarray, list[float]]:
    try:
        k = len(seq)
        k_times = len(times_s)
    except TypeError:
        raise InvalidCommand(f"{op}: {field_name} and times_s must be lists") from None
    if k == 0 or k != k_times:
        raise InvalidCommand(f"{op}: {field_name} and times_s must be non-empty and of equal length; "
                             f"got {k} poses and {k_times} times")
    goals = np.stack([_vector(op, f"{field_name}[{i}]", q, n, f"{n} angles [rad]")
                      for i, q in enumerate(seq)])
    times = [_time(op, f"times_s[{i}]", t) for i, t in enumerate(times_s)]
    return goals, times
