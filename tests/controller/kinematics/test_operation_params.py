"""The operation IK's parameters: each with a unit and a range, validated when built."""

import dataclasses

import pytest

from controller.core.errors import InvalidCommand
from controller.kinematics.operation_params import OperationIKParams


def test_every_parameter_has_a_unit_and_a_range():
    for f in dataclasses.fields(OperationIKParams):
        assert "unit" in f.metadata and "min" in f.metadata and "max" in f.metadata, f.name
    with pytest.raises(InvalidCommand, match="joint_velocity_limit_rad_s"):
        OperationIKParams(joint_velocity_limit_rad_s=10.0)
