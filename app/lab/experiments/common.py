"""What an experiment is (and the disturbances it accepts), what it reports, and the motions the scripts share
(setJointAngles, hand pushes)."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from app.service import OperatorService
from app.service.local import LocalRobot
from controller.core.loop import Snapshot
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import matrix_to_rpy
from robot.names import joint_index
from robot.plant import MujocoPlant

#: (time after the start [s], the planner's commands at that tick boundary: verbs of the operator service)
Event = tuple[float, Callable[[], None]]


@dataclass
class Rig:
    """What an experiment's planner works with: the operator service (its verbs are the only way to command
    the robot), the latest snapshot, its own kinematic model; and the simulated plant, which only the
    recognition stand-ins and the outcome measures read."""

    service: OperatorService
    robot: LocalRobot

    @property
    def snapshot(self) -> Snapshot:
        return self.robot.loop.snapshot

    @property
    def kin(self) -> RobotKinematics:
        return self.robot.system.kin

    @property
    def plant(self) -> MujocoPlant:
        return self.robot.host.plant


@dataclass(frozen=True)
class DisturbanceParam:
    """One disturbance an experiment accepts: its default (the experiment as docs/estop-study.md describes
    it: no disturbance beyond the variant's), the range it may be set to, its unit and what it changes."""

    default: float
    low: float
    high: float
    unit: str
    description: str

    def __post_init__(self) -> None:
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low <= self.default <= self.high):
            raise ValueError(f"a disturbance's default {self.default} must lie in [{self.low}, {self.high}]")


#: The disturbance values a script gets: every declared name, set or default.
Disturbance = Mapping[str, float]


@dataclass(frozen=True)
class Experiment:
    """`script(rig, variant, disturbance)` gives the timed commands; `place(rig, disturbance)`, when given, sets
    the scene up before the robot settles (simulator operations: the robot put down farther from the wall);
    `outcome(rig)` measures the task at the end (valve angle, door angle, ...) from the simulation, for tests
    and the report. `disturbances` declares what a study may vary (name -> DisturbanceParam); at their
    defaults the experiment is the one docs/estop-study.md describes."""

    scene: str
    script: Callable[[Rig, str, Disturbance], list[Event]]
    duration_s: float
    description: str
    variants: tuple[str, ...] = ("default",)
    impedance: tuple[str, ...] = ()  # limbs whose ImpedanceController runs during the experiment
    outcome: Callable[[Rig], dict[str, float]] | None = None
    disturbances: Mapping[str, DisturbanceParam] = field(default_factory=dict)
    place: Callable[[Rig, Disturbance], None] | None = None

    def disturbance(self, values: Mapping[str, float] | None = None) -> dict[str, float]:
        """`values` checked against the declared disturbances (names, finite, in range) and completed with the
        defaults; ValueError naming the disturbance and what is allowed."""
        values = dict(values or {})
        unknown = sorted(set(values) - set(self.disturbances))
        if unknown:
            valid = ", ".join(self.disturbances) or "none"
            raise ValueError(f"unknown disturbance {unknown[0]!r}; this experiment accepts: {valid}")
        out = {}
        for name, spec in self.disturbances.items():
            value = values.get(name, spec.default)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or not spec.low <= value <= spec.high:
                raise ValueError(f"disturbance {name} must be a number in [{spec.low:g}, {spec.high:g}] "
                                 f"{spec.unit}, got {value!r}")
            out[name] = float(value)
        return out


@dataclass(frozen=True)
class ExperimentResult:
    name: str
    variant: str
    es: bool
    verdict: str  # "stood" | "fell"
    flag_time_s: float | None
    peak_cp_error_m: float
    cp_error_at_flag_m: float | None
    edge_margin_at_flag_m: float | None  # distance of the actual CP to the support edge when the flag rose
    min_edge_margin_m: float  # smallest distance of the actual CP to the support edge (negative: outside)
    below_threshold_after_revert_s: float | None  # from the end of the revert until the error stays < threshold
    duration_s: float
    outcome: dict[str, float] = field(default_factory=dict)
    real_time_factor: float = 0.0  # simulated time (settling included) / wall time spent simulating it
    refused: tuple[str, ...] = ()  # planner commands the robot refused (when, why): e.g. after a motion stop
    faults: tuple[str, ...] = ()  # every distinct controller fault of the run (its RunStats); empty: none
    emergency_steps: int = 0  # capture-point emergency steps the AutoBalancer took (issue 13.3)
    csv_path: str | None = None
    png_path: str | None = None

    def verdict_line(self) -> str:
        flag = "none" if self.flag_time_s is None else f"{self.flag_time_s:.3f} s"
        return f"verdict: {self.verdict} (flag at {flag}, peak CP error {self.peak_cp_error_m * 1e3:.1f} mm)"


def pose_with(rig: Rig, changes_deg: dict[str, float]) -> np.ndarray:
    """The SequencePlayer's current joint angles [rad] with `changes_deg` [deg] applied."""
    q = np.array(rig.snapshot.q_seq_rad, dtype=float)
    for name, deg in changes_deg.items():
        q[joint_index(name)] = math.radians(deg)
    return q


def move_hands(rig: Rig, limbs: tuple[str, ...], delta_world: np.ndarray, time_s: float) -> None:
    """setTargetPose: move each hand by `delta_world` [m] from where the plan has it now, orientation kept
    (hrpsys-style joint-space interpolation)."""
    kin = rig.kin
    snap = rig.snapshot
    ref = snap.reference
    kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, snap.q_seq_rad)
    targets = [(limb, *kin.frame_pose(f"{limb}_end")) for limb in limbs]
    for limb, p, R in targets:
        rig.service.set_target_pose(limb, p + delta_world, matrix_to_rpy(R), time_s)
