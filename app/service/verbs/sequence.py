"""Verbs of the SequencePlayer (hrpsys SequencePlayerService): joint angles, target poses,
sequences."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.service.errors import InvalidArgument
from app.service.verbs.base import Host, RobotInfo, Verb, check_bounded, check_finite, check_motion_time
from robot.names import JOINT_NAMES

MAX_TARGET_POS_M = 5.0  # [m] |pos| components of a setTargetPose target
TARGET_LIMBS = ("rarm", "larm", "rleg", "lleg")


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
        check_finite("angles_deg", self.q_rad)
        check_motion_time("time", self.time_s)

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

    def final_posture(self, q_now_rad: np.ndarray) -> np.ndarray:
        return np.array(self.q_rad, dtype=float)


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
            check_finite(f"angles_deg.{name}", [v])
        check_motion_time("time", self.time_s)

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

    def final_posture(self, q_now_rad: np.ndarray) -> np.ndarray:
        q = np.array(q_now_rad, dtype=float)
        for name, v in self.angles_rad:
            q[JOINT_NAMES.index(name)] = v
        return q


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
            check_bounded(f"pos.{k}", v, -MAX_TARGET_POS_M, MAX_TARGET_POS_M, "m")
        for k, v in enumerate(self.rpy_rad):
            check_bounded(f"rpy_deg.{k}", v, -math.pi * 2, math.pi * 2, "deg", math.degrees)
        check_motion_time("time", self.time_s)

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
            check_finite("goals", g)
        for t in self.times_s:
            check_motion_time("times", t)

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
            check_finite("postures", q)
        for t in self.times_s:
            check_motion_time("times", t)

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


def held_against(verb, co) -> bool:
    """The CollisionDetector `co` holds the posture and the joint motion `verb` would not free it: refused. One
    whose final posture (on the detector's input for the joints it does not name) is free is how the hold ends, so
    it goes (soak seed 10192: an arm held against a thigh the squat had raised refused `stand` its half-sitting,
    and nothing else could move it)."""
    if co is None or not co.enabled or not co.in_collision:
        return False
    final = getattr(verb, "final_posture", None)
    return final is None or bool(co.checker.colliding_pairs(final(co.q_in)))
