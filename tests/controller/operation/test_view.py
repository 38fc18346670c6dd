"""The operation layer's view: the FK of its last output in F and the world, computed once per tick (unit)."""

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.kinematics.model import RobotKinematics
from controller.operation.body_frame import BodyInFeet
from controller.operation.view import LastTick, ViewOfTick
from controller.system import initial_reference
from robot.generate import half_sitting_deg

REF = initial_reference(RobotKinematics(), np.deg2rad(half_sitting_deg()))


def test_no_view_before_the_first_tick():
    with pytest.raises(InvalidCommand, match="not ticked"):
        ViewOfTick().of(LastTick(), BodyInFeet())


def test_the_view_is_the_outputs_forward_kinematics_and_is_shared_within_a_tick():
    last, frames, views = LastTick(), BodyInFeet(), ViewOfTick()
    last.ref_in, last.time_s = REF, 1.0
    view = views.of(last, frames)
    kin = RobotKinematics()
    kin.update_rpy(REF.base_pos_world, REF.base_rpy_rad, REF.q_rad)
    p, R = kin.frame_pose("rarm_end")
    assert np.allclose(view.points["rhand"].p_world_m, p) and np.allclose(view.points["rhand"].R_world_point, R)
    assert view.lsole_from_rsole == (0.0, 0.19, 0.0) and view.time_s == 1.0  # no gait: the default
    assert views.of(last, frames) is view
    last.stopped = True  # another tick's state: a new view
    again = views.of(last, frames)
    assert again is not view and again.motion_stopped
