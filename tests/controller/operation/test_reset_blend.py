"""After reset_targets(): the output blends from the last one onto the reference, then is the reference (unit)."""

import numpy as np
import pytest

from controller.kinematics.model import RobotKinematics
from controller.operation.reset_blend import ResetBlend
from controller.system import initial_reference
from robot.generate import half_sitting_deg

REF = initial_reference(RobotKinematics(), np.deg2rad(half_sitting_deg()))


def test_the_output_goes_from_the_last_one_to_the_reference_by_a_min_jerk_weight():
    last = REF.with_(q_rad=REF.q_rad + 0.1, base_pos_world=REF.base_pos_world + (0.0, 0.0, -0.02))
    blend = ResetBlend()
    assert not blend.pending
    blend.start(last, 0.1)
    outs = []
    while blend.pending:
        outs.append(blend.step(REF, 0.01))
    assert outs[-1] is REF and len(outs) in (10, 11)  # (ten steps of 0.01 s sum to a hair under 0.1)
    offsets = [float(o.q_rad[0] - REF.q_rad[0]) for o in outs[:-1]]
    assert 0.0 <= offsets[-1] < offsets[0] < 0.1 and offsets == sorted(offsets, reverse=True)  # monotone
    assert np.allclose(outs[4].base_pos_world[2] - REF.base_pos_world[2], -0.02 * offsets[4] / 0.1)  # one weight


def test_a_cancelled_blend_is_no_longer_pending():
    blend = ResetBlend()
    blend.start(REF, 1.0)
    blend.cancel()
    assert not blend.pending


def test_a_reset_is_as_slow_as_its_largest_offset_asks_and_never_quicker_than_asked():
    from controller.operation.reset_blend import (
        RESET_HEIGHT_SPEED_M_S,
        RESET_JOINT_RATE_RAD_S,
        RESET_TILT_RATE_RAD_S,
        reset_duration_s,
    )

    assert reset_duration_s(REF, REF, 1.0) == 1.0
    tilted = REF.with_(base_rpy_rad=REF.base_rpy_rad + (0.0, np.radians(12.0), 0.0))  # soak seed 10110's waist
    assert reset_duration_s(tilted, REF, 1.0) == pytest.approx(np.radians(12.0) / RESET_TILT_RATE_RAD_S)  # 2.1 s
    low = REF.with_(base_pos_world=REF.base_pos_world + (0.0, 0.0, -0.1))
    assert reset_duration_s(low, REF, 1.0) == pytest.approx(0.1 / RESET_HEIGHT_SPEED_M_S)
    arm = REF.with_(q_rad=REF.q_rad + np.where(np.arange(len(REF.q_rad)) == 20, 1.5, 0.0))
    assert reset_duration_s(arm, REF, 1.0) == pytest.approx(1.5 / RESET_JOINT_RATE_RAD_S)
    assert reset_duration_s(arm, REF, 5.0) == 5.0
