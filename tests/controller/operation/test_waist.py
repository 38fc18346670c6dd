"""The waist point as the reference's BODY height and rpy, held where the AutoBalancer's legs still reach (unit)."""

import numpy as np
import pytest

from controller.core.types import GaitState
from controller.kinematics.model import RobotKinematics
from controller.operation.frame import PlanarFrame
from controller.operation.point_targets import PointTargets
from controller.operation.targets import WaistPose, feet_frame
from controller.operation.waist import WAIST_MAX_TILT_RAD, WaistPoint, ground_z, tilt_rad
from controller.system import initial_reference
from robot.generate import half_sitting_deg

REF = initial_reference(RobotKinematics(), np.deg2rad(half_sitting_deg()))


def gait(contact=(True, True)):
    kin = RobotKinematics()
    kin.update_rpy(REF.base_pos_world, REF.base_rpy_rad, REF.q_rad)
    (pr, Rr), (pl, Rl) = kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")
    pl = pl + (0.0, 0.0, 0.0 if contact[1] else 0.03)  # the left sole up while it swings
    z = np.zeros(3)
    cog = (pr + pl) / 2
    return GaitState(walking=False, support="both", contact=contact, p_rsole_world=pr, R_rsole_world=Rr,
                     p_lsole_world=pl, R_lsole_world=Rl, zmp_world=z, cog_world=cog, cog_vel_world=z,
                     cog_pc_world=cog, base_pos_world=REF.base_pos_world, base_rpy_rad=REF.base_rpy_rad)


def test_the_waist_height_counts_from_F_or_from_the_stance_sole_while_one_swings():
    F = PlanarFrame(np.array((0.0, 0.0, 0.1)), 0.0)
    assert ground_z(None, F) == 0.1
    g = gait((True, False))
    assert ground_z(g, F) == float(g.p_rsole_world[2])


def test_without_a_gait_the_target_is_BODYs_height_above_F_and_its_rpy():
    pts = PointTargets()
    pts.targets["waist"] = WaistPose(0.6, (0.0, 0.05, 0.0))
    F = PlanarFrame(np.array((0.0, 0.0, 0.01)), 0.0)
    base, rpy = WaistPoint().realise(pts, REF, None, F, False)
    assert base[2] == pytest.approx(0.61) and np.allclose(base[:2], REF.base_pos_world[:2])
    assert np.allclose(rpy, (0.0, 0.05, 0.0)) and pts.achieved["waist"] is pts.targets["waist"]


def test_a_height_the_legs_cannot_reach_is_held_at_the_achieved_one():
    pts = PointTargets()
    g = gait()
    F = PlanarFrame(*feet_frame(
        g.p_rsole_world, g.R_rsole_world, g.p_lsole_world, g.R_lsole_world))
    height = float(REF.base_pos_world[2] - F.p[2])
    reachable = WaistPose(height - 0.01, (0.0, 0.0, 0.0))
    waist = WaistPoint()
    pts.targets["waist"] = reachable
    waist.realise(pts, REF, g, F, False)
    assert pts.targets["waist"] is reachable and pts.limited.get("waist") is None
    pts.targets["waist"] = WaistPose(height + 0.3, (0.0, 0.0, 0.0))  # legs stretched past their length
    base, _ = waist.realise(pts, REF, g, F, False)
    assert pts.targets["waist"] is reachable and pts.limited["waist"] == "reach"
    assert base[2] == pytest.approx(F.p[2] + height - 0.01)
    waist.realise(pts, REF, g, F, True)
    assert pts.limited["waist"] == "motion_stop"


def test_a_tilt_the_fall_detector_would_read_as_a_fall_is_held_at_the_achieved_one():
    # soak seed 11019: a waist stick on one foot tilted BODY to 30 deg, the robot standing; the loop declared a fall
    assert np.degrees(WAIST_MAX_TILT_RAD) == pytest.approx(25.0)
    pts = PointTargets()
    F = PlanarFrame(np.array((0.0, 0.0, 0.0)), 0.0)
    waist = WaistPoint()
    a = WAIST_MAX_TILT_RAD
    within = WaistPose(0.6, (0.0, a - 0.01, 0.3))
    pts.targets["waist"] = within
    waist.realise(pts, REF, None, F, False)
    assert pts.targets["waist"] is within and pts.limited.get("waist") is None
    for rpy in ((0.0, a + 0.01, 0.0), (-(a + 0.01), 0.0, 0.0), (0.7 * a, 0.75 * a, 1.0)):  # pitch, roll, both
        assert tilt_rad(rpy) > a
        pts.targets["waist"] = WaistPose(0.6, rpy)
        _, got = waist.realise(pts, REF, None, F, False)
        assert pts.targets["waist"] is within and pts.limited["waist"] == "reach"
        assert np.allclose(got, within.rpy_rad)
