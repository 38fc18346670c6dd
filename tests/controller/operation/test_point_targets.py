"""The operated points' targets: integrated from their twists, settled on what the IK achieved, re-anchored (unit)."""

import numpy as np
import pytest

from controller.layers.operation import OperationParams
from controller.operation.point_targets import PointTargets
from controller.operation.points import Twist
from controller.operation.targets import GazeAngles, HandPose

DT = 0.005
P = OperationParams()
HAND = HandPose.of((0.3, -0.2, 0.8), np.eye(3))


def seeded(points):
    """seed() for integrate(): the hand at HAND, the gaze straight ahead; records what it seeded."""
    calls = []

    def seed(point):
        calls.append(point)
        return HAND if point in ("rhand", "lhand") else GazeAngles(0.0, 0.0)
    return seed, calls


def test_a_point_is_seeded_at_its_first_twist_and_a_point_at_rest_is_left_alone():
    pts = PointTargets()
    seed, calls = seeded(pts)
    stepped = pts.integrate({"rhand": Twist.of((0.1, 0.0, 0.0)), "lhand": Twist.of()}, P, DT, seed)
    assert calls == ["rhand"] and set(pts.targets) == {"rhand"}  # a zero twist operates nothing
    assert stepped == {"rhand": HAND}  # the hand's target before the step
    assert pts.targets["rhand"].p_feet_m[0] == pytest.approx(0.3 + P.hand_accel_m_s2 * DT * DT)  # ramping up
    assert pts.limited["rhand"] is None and "rhand" in pts.rates


def test_a_point_whose_twist_ends_slows_down_to_rest_then_holds():
    pts = PointTargets()
    seed, _ = seeded(pts)
    for _ in range(40):
        pts.integrate({"rhand": Twist.of((0.1, 0.0, 0.0))}, P, DT, seed)
    x = [pts.targets["rhand"].p_feet_m[0]]
    for _ in range(60):
        pts.integrate({}, P, DT, seed)
        x.append(pts.targets["rhand"].p_feet_m[0])
    steps = np.diff(x)
    assert steps[0] > 0.0 and np.all(np.diff(steps) <= 1e-15)  # decelerating
    assert steps[-1] == 0.0 and not pts.rates  # at rest: no rate left


def test_a_too_fast_twist_is_limited_for_velocity():
    pts = PointTargets()
    seed, _ = seeded(pts)
    pts.integrate({"head": Twist.of(angular_rad_s=(0.0, 0.0, 3.0))}, P, 1.0, seed)  # one long tick: past the ramp
    assert pts.limited["head"] == "velocity"


def test_settle_clamps_a_limited_target_or_advances_a_hand_along_its_step():
    pts = PointTargets()
    pts.targets = {"rhand": HandPose.of((0.4, -0.2, 0.8), np.eye(3)), "head": GazeAngles(0.3, 0.0)}
    pts.limited = {"rhand": "velocity", "head": None}
    half_way_and_off = HandPose.of((0.35, -0.15, 0.8), np.eye(3))
    pts.settle("rhand", half_way_and_off, "reach", False, {"rhand": HAND})
    assert np.allclose(pts.targets["rhand"].p_feet_m, (0.35, -0.2, 0.8))  # the share along x, not sideways
    assert pts.limited["rhand"] == "reach" and pts.achieved["rhand"] is half_way_and_off
    pts.settle("head", GazeAngles(0.2, 0.0), "joint_limit", False, {})
    assert pts.targets["head"] == GazeAngles(0.2, 0.0)  # clamped to the achieved gaze
    pts.settle("head", GazeAngles(0.2, 0.0), None, True, {})
    assert pts.limited["head"] == "motion_stop"
    pts.limited["head"] = "velocity"
    pts.settle("head", GazeAngles(0.2, 0.0), None, False, {})
    assert pts.limited["head"] == "velocity"  # the IK followed: the speed limit of this tick stays the reason


def test_re_anchoring_moves_the_hands_and_the_neck_not_the_gaze():
    pts = PointTargets()
    pts.targets = {"rhand": HAND, "head": GazeAngles(0.1, 0.2)}
    pts.achieved = {"rhand": HAND}
    pts.neck_feet_m = np.array((0.0, 0.0, 0.5))
    body = np.array((0.01, 0.02, 0.7))
    pts.re_anchor(True, body)
    pts.anchor = body
    assert pts.anchored_walking
    assert np.allclose(pts.targets["rhand"].p_feet_m, HAND.p_feet_m - body)
    assert np.allclose(pts.achieved["rhand"].p_feet_m, HAND.p_feet_m - body)
    assert np.allclose(pts.neck_feet_m, (-0.01, -0.02, -0.2)) and pts.targets["head"] == GazeAngles(0.1, 0.2)
    pts.clear()
    assert not (pts.targets or pts.achieved or pts.limited or pts.rates)
