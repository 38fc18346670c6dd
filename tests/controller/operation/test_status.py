"""The operation layer's status built from its pieces: targets, achieved poses, reasons, the two twists (unit)."""

import numpy as np

from controller.operation.command_sum import CommandSum
from controller.operation.point_targets import PointTargets
from controller.operation.points import POINTS, Twist
from controller.operation.status import operation_status
from controller.operation.targets import GazeAngles
from controller.operation.walk_point import WalkPoint


def test_nothing_operated_reads_as_zero_twists_and_no_targets():
    st = operation_status(True, False, CommandSum(), PointTargets(), WalkPoint())
    assert not st.active and list(st.points) == list(POINTS)
    assert all(ps.target is None and ps.motion == (0.0,) * 6 for ps in st.points.values())


def test_the_points_twists_targets_and_reasons_are_reported():
    commands, points, walk = CommandSum(), PointTargets(), WalkPoint()
    commands.streamed.set("head", Twist.of(angular_rad_s=(0.0, 0.1, 0.0)), 0.0)
    commands.set_behavior({"walk": Twist.of((0.1, 0.0, 0.0))})
    total, _ = commands.take(0.0, 0.2, 0.1)
    walk.command(total["walk"], None, 0.3, 0.5)
    points.targets["head"], points.achieved["head"] = GazeAngles(0.2, 0.1), GazeAngles(0.15, 0.1)
    points.limited = {"head": "joint_limit", "rhand": "reach"}  # a reason without a target is not reported
    st = operation_status(True, True, commands, points, walk).to_dict()
    head = st["points"]["head"]
    assert st["active"] and st["motion_stopped"]
    assert head["target"] == [0.2, 0.1] and head["achieved"] == [0.15, 0.1] and head["limited"] == "joint_limit"
    assert np.allclose(head["motion"], (0, 0, 0, 0, 0.1, 0)) and st["points"]["rhand"]["limited"] is None
    assert np.allclose(st["points"]["walk"]["target"], (0.1, 0.0, 0.0))
    assert np.allclose(st["points"]["walk"]["behavior"], (0.1, 0, 0, 0, 0, 0))


def test_the_points_are_built_when_read_from_the_state_as_it_was_when_the_status_was_taken():
    import pickle

    from controller.core.layer import plain
    from controller.operation.targets import HandPose

    commands, points = CommandSum(), PointTargets()
    hand = HandPose.of((0.3, -0.2, 0.8), np.eye(3))
    points.targets["rhand"] = points.achieved["rhand"] = hand
    points.anchor = np.array((0.01, 0.0, 0.0))  # walking: the hands held relative to BODY
    status = operation_status(True, False, commands, points, WalkPoint())
    assert type(status.__dict__["_points_value"]).__name__ == "BuildLater"  # not built yet
    points.targets["rhand"] = HandPose.of((0.5, 0.0, 0.8), np.eye(3))  # the next tick
    points.limited["rhand"], points.anchor = "reach", np.zeros(3)
    rhand = status.points["rhand"]
    assert np.allclose(rhand.target[:3], (0.31, -0.2, 0.8)) and rhand.limited is None  # the anchor added back
    assert status.points["waist"].target is None and len(status.points) == len(POINTS)
    assert type(status.points) is dict and status.points["rhand"] is rhand  # built once
    copy = pickle.loads(pickle.dumps(status))
    assert copy == status and type(copy.points) is dict
    assert plain(status)["points"]["rhand"]["target"] == list(rhand.target)  # what the state document reads


def test_each_points_dead_man_state_is_reported_streaming_ramping_then_stopped():
    commands = CommandSum()
    commands.streamed.set("rhand", Twist.of((0.05, 0.0, 0.0)), 0.0)

    def deadman_at(t: float) -> dict:
        commands.take(t, 0.2, 0.1)
        pts = operation_status(True, False, commands, PointTargets(), WalkPoint()).to_dict()["points"]
        return {p: pts[p]["deadman"] for p in ("rhand", "head")}

    assert deadman_at(0.1) == {"rhand": "streaming", "head": "stopped"}  # fresh (never streamed: stopped)
    ramping = deadman_at(0.25)  # past the 0.2 s timeout, fading over 0.1 s
    assert ramping == {"rhand": "ramping", "head": "stopped"}
    assert deadman_at(0.31) == {"rhand": "stopped", "head": "stopped"}  # faded out
