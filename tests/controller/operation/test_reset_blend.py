"""After reset_targets(): the output blends from the last one onto the reference, then is the reference (unit)."""

import numpy as np

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
