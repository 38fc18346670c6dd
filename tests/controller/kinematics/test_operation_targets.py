"""The operation IK's targets and results: validated once with what would work, kept as floats, read-only."""

import math

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.kinematics import operation_ik
from controller.kinematics.operation_targets import (
    FeetPoses,
    GazeTarget,
    HandTarget,
    OperationTargets,
    WaistTarget,
)
from controller.kinematics.rotations import rpy_to_matrix


def test_invalid_targets_are_rejected_with_what_would_work():
    with pytest.raises(InvalidCommand, match="3 finite numbers"):
        HandTarget([0.0, 0.0], np.eye(3))
    with pytest.raises(InvalidCommand, match="not a rotation"):
        HandTarget([0.0, 0.0, 0.0], 2 * np.eye(3))
    with pytest.raises(InvalidCommand, match="at least one True"):
        FeetPoses(np.zeros(3), np.eye(3), np.zeros(3), np.eye(3), (False, False))
    with pytest.raises(InvalidCommand, match="finite"):
        GazeTarget(yaw_rad=float("nan"))


def test_a_hand_target_keeps_its_pose_as_read_only_arrays_and_as_floats():
    R = rpy_to_matrix([0.1, 0.2, 0.3])
    t = HandTarget([0.1, 0.2, 0.3], R)
    assert not t.p_world.flags.writeable and not t.R_world.flags.writeable
    assert t.rows == ((0.1, 0.2, 0.3), tuple(map(tuple, R.tolist())))
    assert HandTarget.from_rows(*t.rows).rows == t.rows
    assert HandTarget.trusted(t.p_world, t.R_world).rows == t.rows


def test_the_soles_are_kept_as_planar_poses_and_the_waist_as_rotation_rows():
    feet = FeetPoses((0.0, -0.1, 0.0), rpy_to_matrix([0.0, 0.0, 0.3]), (0.0, 0.1, 0.0), np.eye(3), (1, 0))
    assert feet.contact == (True, False)
    assert feet.planar_soles[0] == pytest.approx((0.0, -0.1, 0.3)) and feet.planar_soles[1] == (0.0, 0.1, 0.0)
    waist = WaistTarget(0.6, (0.0, 0.1, 0.0))
    assert np.allclose(waist.R_rows, rpy_to_matrix([0.0, 0.1, 0.0]))


def test_targets_are_active_when_any_point_is_operated():
    assert not OperationTargets().active
    assert OperationTargets(head=GazeTarget(yaw_rad=math.radians(10.0))).active


def test_the_names_the_layer_and_the_tests_import_from_operation_ik_are_still_there():
    for name in ("OperationIK", "OperationIKParams", "HandTarget", "GazeTarget", "WaistTarget", "OperationTargets",
                 "FeetPoses", "PointResult", "OperationIKResult", "POINTS", "REACH", "JOINT_LIMIT", "VELOCITY",
                 "SOLVER", "HAND_FRAMES", "FOOT_FRAMES"):
        assert hasattr(operation_ik, name), name
    assert operation_ik.HandTarget is HandTarget
