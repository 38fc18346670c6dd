"""What a behaviour is about to do, before it moves the robot (MoveIt's plan preview): its planned footsteps
and hand paths in the world, phase by phase, computed by the behaviour's own code (its `preview`, a
composite's own `plan` generator, the AutoBalancer's own footstep planner) on a predicted view of the robot:
each step is assumed to end where it is planned to. A plan that reads a sensor (the wrist force, a jaw angle,
a camera) cannot be followed further without moving: the preview ends there and says so (`ends`)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from controller.operation.points import OperationView, PointPose

HAND_PATH_POINTS = 12  # points drawn along one hand's straight line


class PreviewEnds(Exception):
    """The plan needs what only the motion can tell (a sensor reading): the preview stops there."""


@dataclass(frozen=True, slots=True)
class PlannedStep:
    """One footstep as planned, in the world: the sole's centre [m] and heading [rad]."""

    side: str  # "right" | "left"
    x_m: float
    y_m: float
    yaw_rad: float

    def to_dict(self) -> dict[str, Any]:
        return {"side": self.side, "x_m": round(self.x_m, 5), "y_m": round(self.y_m, 5),
                "yaw_rad": round(self.yaw_rad, 6)}


@dataclass
class MotionPreview:
    """The planned motion of one behaviour: footsteps, hand paths (world [m]) and the phases they belong to."""

    behavior: str
    footsteps: list[tuple[str, PlannedStep]] = field(default_factory=list)  # (phase, step)
    hand_paths: list[tuple[str, str, np.ndarray]] = field(default_factory=list)  # (phase, hand, (n, 3) world)
    phases: list[dict[str, Any]] = field(default_factory=list)  # {"phase", "behavior"} in plan order
    ends: str = ""  # why the preview stops before the plan's end ("" when it reaches it)

    def to_dict(self) -> dict[str, Any]:
        return {"behavior": self.behavior,
                "footsteps": [{**s.to_dict(), "phase": ph} for ph, s in self.footsteps],
                "hand_paths": [{"phase": ph, "hand": hand, "points_m": np.round(pts, 5).tolist()}
                               for ph, hand, pts in self.hand_paths],
                "phases": list(self.phases), "complete": not self.ends, "ends": self.ends}


@dataclass
class Predicted:
    """The robot as the plan so far leaves it: the operation view, and the soles once a walk is planned
    (None: where they are now)."""

    view: OperationView
    soles: tuple[PlannedStep, PlannedStep] | None = None  # (right, left), world


def _rot_z(yaw_rad: float) -> np.ndarray:
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))


def feet_moved(view: OperationView, x_m: float, y_m: float, yaw_rad: float) -> OperationView:
    """`view` with the feet frame F at (x, y, yaw) of the world: the points keep their poses in F."""
    p_f = np.array((x_m, y_m, float(view.feet_p_world_m[2])))
    R = _rot_z(yaw_rad)
    points = {name: PointPose(p_world_m=p_f + R @ pose.p_feet_m, R_world_point=R @ pose.R_feet_point,
                              p_feet_m=pose.p_feet_m, R_feet_point=pose.R_feet_point)
              for name, pose in view.points.items()}
    return dataclasses.replace(view, feet_p_world_m=p_f, feet_yaw_rad=float(yaw_rad), points=points)


def point_moved(view: OperationView, point: str, p_feet_m, R_feet_point) -> OperationView:
    """`view` with one operational point at a pose of the feet frame F."""
    R = _rot_z(view.feet_yaw_rad)
    p = np.asarray(p_feet_m, dtype=float)
    pose = PointPose(p_world_m=np.asarray(view.feet_p_world_m, dtype=float) + R @ p,
                     R_world_point=R @ R_feet_point, p_feet_m=p, R_feet_point=np.asarray(R_feet_point))
    return dataclasses.replace(view, points={**view.points, point: pose})


def line_in_world(view: OperationView, p0_feet_m, p1_feet_m, n: int = HAND_PATH_POINTS) -> np.ndarray:
    """(n, 3) points of the straight line p0 -> p1 (feet frame F) in the world."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    line_f = np.asarray(p0_feet_m, dtype=float) + s * (np.asarray(p1_feet_m, dtype=float) - p0_feet_m)
    return np.asarray(view.feet_p_world_m, dtype=float) + line_f @ _rot_z(view.feet_yaw_rad).T


def mid_of(right: PlannedStep, left: PlannedStep) -> tuple[float, float, float]:
    """The feet frame (x, y, yaw) between two soles (the mean heading)."""
    dyaw = math.atan2(math.sin(left.yaw_rad - right.yaw_rad), math.cos(left.yaw_rad - right.yaw_rad))
    return 0.5 * (right.x_m + left.x_m), 0.5 * (right.y_m + left.y_m), right.yaw_rad + 0.5 * dyaw


def last_soles(steps: list[PlannedStep], before: tuple[PlannedStep, PlannedStep] | None
               ) -> tuple[PlannedStep, PlannedStep] | None:
    """(right, left) where a walk of `steps` leaves the feet (the last of each side; `before` for a side that
    does not step)."""
    right = next((s for s in reversed(steps) if s.side == "right"), before[0] if before else None)
    left = next((s for s in reversed(steps) if s.side == "left"), before[1] if before else None)
    return None if right is None or left is None else (right, left)


class PreviewCommands:
    """The command interface a plan sees while it is previewed: the footstep planner and the remembered
    recognitions are the robot's own; anything that would move the robot or read a sensor ends the preview."""

    def __init__(self, commands: Any) -> None:
        self._commands = commands

    def plan_go_pos(self, x_m: float, y_m: float, theta_rad: float, soles=None) -> list[PlannedStep]:
        return self._commands.plan_go_pos(x_m, y_m, theta_rad, soles)

    def recalled(self, object_name: str):
        found = self._commands.recalled(object_name)
        if found is None:
            raise PreviewEnds(f"where the {object_name} is is not known before it is located")
        return found

    def wrench(self, sensor: str):
        raise PreviewEnds(f"what follows depends on the {sensor} force sensor's reading during the motion")

    def joint(self, name: str):
        raise PreviewEnds(f"what follows depends on {name}'s encoder during the motion")

    def capture(self, camera: str, analyse=None):
        raise PreviewEnds(f"what follows depends on the {camera} camera's image")

    def __getattr__(self, name: str):
        raise PreviewEnds(f"the plan commands {name} itself, outside its steps: not previewed")
