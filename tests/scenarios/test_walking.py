"""Walking in simulation with the AutoBalancer and the Stabilizer on: goPos accuracy, long walks,
turning, goVelocity, toe-heel footsteps, the emergency walking stop; the body stays upright (|roll|, |pitch|
within MAX_TILT_DEG, measured)."""

import numpy as np
import pytest

from controller.walking.footsteps import StepParams
from robot.names import JOINT_GROUPS, joint_index
from tests.scenarios.helpers import HALF_SITTING_DEG, make_system, pose_deg, seq_call

#: [deg] worst |roll|, |pitch| of BODY (simulated) on every walk below: measured 0.59-0.77 deg (goPos(0.1, 0.1,
#: 20 deg) 0.77, goPos(-0.1, -0.1, -10 deg) 0.73, 3 m 0.73, 1 m left 0.76, turn 180 deg 0.74, goVelocity 0.70,
#: emergency walking stop 0.59), margin 30 %.
MAX_TILT_DEG = 1.0
#: [deg] the same with toe 20 deg / heel 10 deg footsteps: measured 1.05 deg, margin 30 %.
TOE_HEEL_MAX_TILT_DEG = 1.35


def roll_pitch_deg(quat_wxyz):
    w, x, y, z = quat_wxyz
    roll = np.degrees(np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)))
    pitch = np.degrees(np.arcsin(np.clip(2 * (w * y - z * x), -1, 1)))
    return roll, pitch


class Walker:
    """A simulated HRP-2 standing 2.5 s (AutoBalancer and Stabilizer blended in), then commanded."""

    def __init__(self):
        self.system = make_system()
        self.loop = self.system.loop
        self.abc = self.system.chain["abc"]
        self.loop.run_for(2.5)
        self.worst_deg = 0.0

    def call(self, fn):
        return self.loop.call(fn)

    def run(self, seconds):
        snap = self.loop.snapshot
        for _ in range(int(round(seconds / self.loop.dt_control_s))):
            snap = self.loop.step()
            self.worst_deg = max(self.worst_deg, *np.abs(roll_pitch_deg(snap.truth.base_quat_wxyz)))
            assert not snap.fallen, f"fell at t={snap.time_s:.2f} s"
        return snap

    def walk_until_stopped(self, timeout_s):
        self.run(0.1)
        for _ in range(int(timeout_s / 0.5)):
            if not self.abc.gait.walking:
                return self.run(0.5)
            self.run(0.5)
        raise AssertionError(f"still walking after {timeout_s} s")

    def sole_truth_R(self, site):
        """Simulated sole frame orientation (3, 3) of the MuJoCo site."""
        d, m = self.loop.plant.data, self.loop.plant.model
        return d.site_xmat[m.site(site).id].reshape(3, 3).copy()

    def sole_truth(self, site):
        """Simulated sole frame: position and yaw of the MuJoCo site."""
        d, m = self.loop.plant.data, self.loop.plant.model
        sid = m.site(site).id
        R = d.site_xmat[sid].reshape(3, 3)
        return d.site_xpos[sid].copy(), np.arctan2(R[1, 0], R[0, 0])


def sole_pitch_deg(R) -> float:
    """Pitch [deg] of a sole frame: positive heel up (toe-off), negative toe up (heel strike)."""
    return float(np.degrees(np.arctan2(-R[2, 0], R[2, 2])))


def mid_coords(T_r, T_l):
    yaw_r, yaw_l = np.arctan2(T_r[1, 0], T_r[0, 0]), np.arctan2(T_l[1, 0], T_l[0, 0])
    yaw = np.arctan2(np.sin(yaw_r) + np.sin(yaw_l), np.cos(yaw_r) + np.cos(yaw_l))
    return 0.5 * (T_r[:3, 3] + T_l[:3, 3]), yaw


@pytest.mark.parametrize("goal", [(0.1, 0.1, 20.0), (-0.1, -0.1, -10.0)], ids=["forward-left-20", "back-right-m10"])
def test_go_pos_lands_the_planned_feet_on_the_goal_and_the_simulated_feet_on_the_plan(goal):
    w = Walker()
    gg = w.abc.gait
    p0, yaw0 = mid_coords(gg.T_world_rfoot, gg.T_world_lfoot)
    w.call(lambda: w.abc.go_pos(goal[0], goal[1], np.radians(goal[2])))
    w.walk_until_stopped(20.0)
    p1, yaw1 = mid_coords(gg.T_world_rfoot, gg.T_world_lfoot)
    # 1. the plan: final mid-coords = start composed with the goal (hrpsys checkGoPosParam)
    c, s = np.cos(yaw0), np.sin(yaw0)
    d_local = np.array([[c, s], [-s, c]]) @ (p1[:2] - p0[:2])
    assert np.all(np.abs(d_local - goal[:2]) < 5e-5)
    assert abs(np.degrees(yaw1 - yaw0) - goal[2]) < 0.01
    # 2. the simulation: each sole within 2 cm and 2 deg of its planned final pose
    for site, T in (("rleg_end", gg.T_world_rfoot), ("lleg_end", gg.T_world_lfoot)):
        pos, yaw = w.sole_truth(site)
        assert np.linalg.norm(pos[:2] - T[:2, 3]) < 0.02
        assert abs(np.degrees(yaw - np.arctan2(T[1, 0], T[0, 0]))) < 2.0
    assert w.worst_deg < MAX_TILT_DEG


@pytest.mark.slow
@pytest.mark.parametrize("goal,timeout", [((3.0, 0.0, 0.0), 30.0), ((0.0, 1.0, 0.0), 35.0), ((0.0, 0.0, 180.0), 35.0)],
                         ids=["3m-forward", "1m-left", "turn-180"])
def test_long_walks_and_turning_in_place_never_fall_and_stay_upright(goal, timeout):
    w = Walker()
    w.call(lambda: w.abc.go_pos(goal[0], goal[1], np.radians(goal[2])))
    snap = w.walk_until_stopped(timeout)
    assert w.worst_deg < MAX_TILT_DEG
    # the body ended where the walk was meant to take it (within 10 cm: the feet carry it there)
    if goal[2] == 0.0:
        assert np.linalg.norm(snap.truth.base_pos_world[:2] - np.array(goal[:2])) < 0.1


@pytest.mark.slow
def test_go_velocity_for_twenty_seconds_then_go_stop_never_falls():
    w = Walker()
    w.call(lambda: w.abc.go_velocity(0.1, 0.05, np.radians(10.0)))
    snap = w.run(20.0)
    assert snap.layers["abc"].walking
    moved = np.linalg.norm(snap.truth.base_pos_world[:2])
    w.call(lambda: w.abc.go_stop())
    w.walk_until_stopped(10.0)
    assert moved > 0.5
    assert w.worst_deg < MAX_TILT_DEG


def test_footsteps_with_toe_20_and_heel_10_degrees_walk_upright():
    w = Walker()
    sp = StepParams(toe_angle_rad=np.radians(20.0), heel_angle_rad=np.radians(10.0))
    steps = [("rleg", [0.0, -0.095, 0.0], [0, 0, 0]), ("lleg", [0.2, 0.095, 0.0], [0, 0, 0]),
             ("rleg", [0.4, -0.095, 0.0], [0, 0, 0]), ("lleg", [0.4, 0.095, 0.0], [0, 0, 0])]
    planned, simulated = [], []
    w.call(lambda: w.abc.set_footsteps(steps, [None, sp, sp, sp]))
    for _ in range(800):  # 4 s, every tick: both feet swing with toe-off and heel-strike
        w.run(w.loop.dt_control_s)
        g = w.abc.last_gait
        planned.append([sole_pitch_deg(g.R_rsole_world), sole_pitch_deg(g.R_lsole_world)])
        simulated.append([sole_pitch_deg(w.sole_truth_R(site)) for site in ("rleg_end", "lleg_end")])
    snap = w.walk_until_stopped(10.0)
    planned, simulated = np.array(planned), np.array(simulated)
    # each planned sole pitched to the toe angle (+20 deg, heel up) AND to the heel angle (-10 deg, toe up):
    # measured 20.000 and -10.000 deg on both feet; 0.01 deg is rounding
    np.testing.assert_allclose(planned.max(axis=0), [20.0, 20.0], atol=0.01)
    np.testing.assert_allclose(planned.min(axis=0), [-10.0, -10.0], atol=0.01)
    # and the simulated soles followed: measured toe 20.01 / 19.99 deg, heel -10.42 / -10.25 deg (r / l);
    # margin 0.5 deg
    assert np.all(simulated.max(axis=0) > 19.5) and np.all(simulated.min(axis=0) < -9.5), simulated
    assert w.worst_deg < TOE_HEEL_MAX_TILT_DEG
    assert abs(snap.truth.base_pos_world[0] - 0.4) < 0.05


def test_walking_commands_need_a_running_auto_balancer_and_say_so():
    from controller.core.errors import InvalidState

    w = Walker()
    w.call(lambda: w.abc.stop())
    w.run(2.5)
    with pytest.raises(InvalidState, match="AutoBalancer"):
        w.call(lambda: w.abc.go_pos(0.1, 0.0, 0.0))


RARM, LARM = list(JOINT_GROUPS["rarm"]), list(JOINT_GROUPS["larm"])


def test_emergency_walking_stop_stops_in_place_and_leaves_the_arms_alone():
    """The walking stop cuts the footsteps only: an arm motion under way goes on to its end, the arms are
    commanded exactly as the SequencePlayer plans them, the other arm stays at half-sitting."""
    w = Walker()
    worst_cmd_vs_plan = worst_tracking = worst_larm = 0.0

    def run(seconds):
        nonlocal worst_cmd_vs_plan, worst_tracking, worst_larm
        snap = None
        for _ in range(int(round(seconds / w.loop.dt_control_s))):
            snap = w.run(w.loop.dt_control_s)
            cmd, meas, seq = (np.rad2deg(np.asarray(q)) for q in (snap.q_cmd_rad, snap.q_meas_rad, snap.q_seq_rad))
            worst_cmd_vs_plan = max(worst_cmd_vs_plan, float(np.abs(cmd[RARM + LARM] - seq[RARM + LARM]).max()))
            worst_tracking = max(worst_tracking, float(np.abs(meas[RARM + LARM] - cmd[RARM + LARM]).max()))
            worst_larm = max(worst_larm, float(np.abs(meas[LARM] - HALF_SITTING_DEG[LARM]).max()))
        return snap

    w.call(lambda: w.abc.go_velocity(0.1, 0.0, 0.0))
    run(1.7)
    target = pose_deg(RARM_JOINT0=-40.0, RARM_JOINT3=-30.0)
    seq_call(w.system, "set_joint_angles", np.deg2rad(target), 2.0)  # the right arm moves while walking
    run(0.5)
    start_x = w.abc.gait.T_world_rfoot[0, 3]
    w.call(lambda: w.abc.emergency_stop_walking())
    snap = run(0.1)
    assert snap.layers["seq"].interpolating  # the arm motion is not stopped with the walk
    while w.abc.gait.walking:
        run(0.5)
    snap = run(0.5)
    end_x = max(w.abc.gait.T_world_rfoot[0, 3], w.abc.gait.T_world_lfoot[0, 3])
    assert end_x - start_x < 0.35  # at most the steps already committed
    assert w.worst_deg < MAX_TILT_DEG
    # the arms are the SequencePlayer's: measured |cmd - seq| 0 exactly on every tick (nothing after it in
    # the chain changes an arm here); 1e-9 deg is rounding
    assert worst_cmd_vs_plan < 1e-9
    # the right arm got to its target: the command exactly, the encoders within 0.35 deg (measured 0.25 deg:
    # the servo's steady error under the arm's weight; margin 40 %)
    cmd, meas = np.rad2deg(np.asarray(snap.q_cmd_rad)), np.rad2deg(np.asarray(snap.q_meas_rad))
    np.testing.assert_allclose(cmd[joint_index("RARM_JOINT0")], -40.0, atol=1e-9)
    assert np.abs(meas[RARM] - target[RARM]).max() < 0.35
    # the servos followed all along: measured lag 1.27 deg at most (the right arm while moving), margin 35 %
    assert worst_tracking < 1.7
    # the left arm, never commanded, stayed at half-sitting: measured 0.12 deg at most (the steps' jolts),
    # margin 50 %
    assert worst_larm < 0.18
