"""Walking in simulation with the AutoBalancer and the Stabilizer on: goPos accuracy, long walks,
turning, goVelocity, toe-heel footsteps; the body stays upright (|roll|, |pitch| < 5 deg)."""

import numpy as np
import pytest

from controller.walking.footsteps import StepParams
from tests.scenarios.helpers import make_system

MAX_TILT_DEG = 5.0


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

    def sole_truth(self, site):
        """Simulated sole frame: position and yaw of the MuJoCo site."""
        d, m = self.loop.plant.data, self.loop.plant.model
        sid = m.site(site).id
        R = d.site_xmat[sid].reshape(3, 3)
        return d.site_xpos[sid].copy(), np.arctan2(R[1, 0], R[0, 0])


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
    pitches = []
    w.call(lambda: w.abc.set_footsteps(steps, [None, sp, sp, sp]))
    for _ in range(40):
        w.run(0.1)
        g = w.abc.last_gait
        pitches.append(np.degrees(np.arctan2(-g.R_rsole_world[2, 0], g.R_rsole_world[2, 2])))
    snap = w.walk_until_stopped(10.0)
    # the planned sole really pitched to the toe and heel angles, and the robot stayed upright
    assert max(pitches) > 10.0 or min(pitches) < -5.0
    assert w.worst_deg < MAX_TILT_DEG
    assert abs(snap.truth.base_pos_world[0] - 0.4) < 0.05


def test_walking_commands_need_a_running_auto_balancer_and_say_so():
    from controller.core.errors import InvalidState

    w = Walker()
    w.call(lambda: w.abc.stop())
    w.run(2.5)
    with pytest.raises(InvalidState, match="AutoBalancer"):
        w.call(lambda: w.abc.go_pos(0.1, 0.0, 0.0))


def test_emergency_walking_stop_stops_in_place_and_leaves_the_arms_alone():
    w = Walker()
    w.call(lambda: w.abc.go_velocity(0.1, 0.0, 0.0))
    w.run(2.2)
    start_x = w.abc.gait.T_world_rfoot[0, 3]
    w.call(lambda: w.abc.emergency_stop_walking())
    w.walk_until_stopped(8.0)
    end_x = max(w.abc.gait.T_world_rfoot[0, 3], w.abc.gait.T_world_lfoot[0, 3])
    assert end_x - start_x < 0.35  # at most the steps already committed
    assert w.worst_deg < MAX_TILT_DEG
