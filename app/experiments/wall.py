"""[MLC] IV-C 1, Fig. 8-10: hands pushed into a rigid wall (scene `wall`), ImpedanceController off."""

from __future__ import annotations

import numpy as np

from app.experiments.common import Event, Experiment, move_hands, pose_with
from controller.system import ControllerSystem
from robot.generate import REACH_FORWARD_DEG


def wall_push_forward(system: ControllerSystem, variant: str) -> list[Event]:
    """Fig. 9 (alpha): both hands 0.25 m forward in 4 s, into the wall in front."""
    seq = system.loop.chain["seq"]
    return [
        (0.0, lambda: seq.set_joint_angles(pose_with(system, REACH_FORWARD_DEG), 2.0)),
        (3.0, lambda: move_hands(system, ("rarm", "larm"), np.array([0.25, 0.0, 0.0]), 4.0)),
    ]


EXPERIMENTS: dict[str, Experiment] = {
    "wall-push-forward": Experiment("wall", wall_push_forward, 12.0, wall_push_forward.__doc__),
}
