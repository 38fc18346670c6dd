"""What an experiment is, what it reports, and the motions the scripts share (setJointAngles, hand pushes)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from controller.rotations import matrix_to_rpy
from controller.system import ControllerSystem
from robot.names import joint_index

#: (time after the start [s], command run inside the loop at that tick boundary)
Event = tuple[float, Callable[[], None]]


@dataclass(frozen=True)
class Experiment:
    """`script(system, variant)` gives the timed commands; `outcome(system)` measures the task at the end
    (valve angle, door angle, ...) from the simulation, for tests and the report."""

    scene: str
    script: Callable[[ControllerSystem, str], list[Event]]
    duration_s: float
    description: str
    variants: tuple[str, ...] = ("default",)
    impedance: tuple[str, ...] = ()  # limbs whose ImpedanceController runs during the experiment
    outcome: Callable[[ControllerSystem], dict[str, float]] | None = None


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
    csv_path: str | None = None
    png_path: str | None = None

    def verdict_line(self) -> str:
        flag = "none" if self.flag_time_s is None else f"{self.flag_time_s:.3f} s"
        return f"verdict: {self.verdict} (flag at {flag}, peak CP error {self.peak_cp_error_m * 1e3:.1f} mm)"


def pose_with(system: ControllerSystem, changes_deg: dict[str, float]) -> np.ndarray:
    """The SequencePlayer's current joint angles [rad] with `changes_deg` [deg] applied."""
    q = np.array(system.loop.snapshot.q_seq_rad, dtype=float)
    for name, deg in changes_deg.items():
        q[joint_index(name)] = math.radians(deg)
    return q


def move_hands(system: ControllerSystem, limbs: tuple[str, ...], delta_world: np.ndarray, time_s: float) -> None:
    """setTargetPose: move each hand by `delta_world` [m] from where the plan has it now, orientation kept
    (hrpsys-style joint-space interpolation)."""
    loop = system.loop
    kin = system.kin
    ref = loop.snapshot.reference
    kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, loop.snapshot.q_seq_rad)
    for limb in limbs:
        p, R = kin.frame_pose(f"{limb}_end")
        loop.call(lambda limb=limb, p=p, R=R: loop.chain["seq"].set_target_pose(
            limb, p + delta_world, matrix_to_rpy(R), time_s))
