"""The walking point in simulation: the operator's walk setpoint streamed into the operation layer
(op.set_motion("walk", ...)), published as Ports.walk_command, walks the robot with goVelocity semantics,
also while the hands and the head are teleoperated; goPos while walking re-plans.

Distances and poses are measured on the simulated soles (MuJoCo sites), which the controller never reads."""

import math

import numpy as np
import pytest

from controller.core.types import WalkCommand
from tests.scenarios import walk_point
from tests.scenarios.test_walking import MAX_TILT_DEG, Walker

#: [deg] worst |roll|, |pitch| of BODY walking 0.1 m/s forward for 10 s with plain goVelocity: measured 0.67;
#: the walking point must stay within it plus a margin of 0.5 deg
PLAIN_GO_VELOCITY_TILT_DEG = 0.67
TILT_MARGIN_DEG = 0.5


def measured_mid(w):
    """Mid-coords (x, y, yaw) of the simulated soles."""
    (pr, yr), (pl, yl) = w.sole_truth("rleg_end"), w.sole_truth("lleg_end")
    return 0.5 * (pr[0] + pl[0]), 0.5 * (pr[1] + pl[1]), math.atan2(math.sin(yr) + math.sin(yl),
                                                                    math.cos(yr) + math.cos(yl))


def feet_side_by_side(w):
    """The left sole in the right sole's frame (x, y [m], yaw [deg]), measured."""
    (pr, yr), (pl, yl) = w.sole_truth("rleg_end"), w.sole_truth("lleg_end")
    c, s = math.cos(yr), math.sin(yr)
    d = pl[:2] - pr[:2]
    return c * d[0] + s * d[1], -s * d[0] + c * d[1], math.degrees(yl - yr)


@pytest.fixture
def walker():
    w = Walker()
    w.point = walk_point.install(w.loop)
    return w


@pytest.mark.slow
def test_walking_point_at_0_1_m_s_for_10_s_walks_1_m_upright_and_stops_with_the_feet_together(walker):
    w = walker
    x0, y0, _ = measured_mid(w)
    w.point.command = WalkCommand(0.1, 0.0, 0.0)
    w.run(10.0)
    # 1. ten seconds at 0.1 m/s: ten 0.1 m steps planned (the first second is the initial double support,
    #    the goStop's aligning step adds none forward)
    w.point.command = None
    w.walk_until_stopped(10.0)
    x1, y1, _ = measured_mid(w)
    # measured 1.023 m (the soles land ~2 cm ahead of the plan), bound 1.0 +- 0.05 m; sideways drift bound 3 cm
    assert abs((x1 - x0) - 1.0) < 0.05 and abs(y1 - y0) < 0.03
    # 2. no fall (Walker.run asserts it) and the body as upright as with plain goVelocity
    assert w.worst_deg < PLAIN_GO_VELOCITY_TILT_DEG + TILT_MARGIN_DEG
    # 3. going to zero stopped it with the feet side by side: measured within 1 cm / 1 deg (bounds)
    dx, dy, dyaw = feet_side_by_side(w)
    assert abs(dx) < 0.01 and abs(dy - 0.19) < 0.01 and abs(dyaw) < 1.0
    assert w.abc.status().walk_point == "idle"


@pytest.mark.slow
def test_walking_at_0_1_m_s_for_10_s_while_the_hands_and_head_are_teleoperated_stays_upright(walker):
    """[OP] V-A / issue 10 Done-when: walk through op.set_motion while both hands and the head are moved."""
    w = walker
    x0, _, _ = measured_mid(w)
    w.point.also = walk_point.hands_and_head
    w.point.command = WalkCommand(0.1, 0.0, 0.0)
    w.run(10.0)  # Walker.run asserts no fall at every tick
    w.point.command = None
    w.walk_until_stopped(10.0)
    x1, _, _ = measured_mid(w)
    op = w.system.chain["op"].status().to_dict()["points"]
    assert op["rhand"]["target"] is not None and op["head"]["target"] is not None  # they were operated
    # measured 1.02 m, as without the hands; bound 1.0 +- 0.05 m
    assert abs((x1 - x0) - 1.0) < 0.05
    # measured worst tilt 0.75 deg (plain walking 0.67); bound: plain + 0.5 deg
    assert w.worst_deg < PLAIN_GO_VELOCITY_TILT_DEG + TILT_MARGIN_DEG


def mid_strides(steps, leg_offset_y_m=0.095):
    """Per footstep k >= 1, the mid-coords displacement (dx, dy, dyaw) it makes, in the previous mid's frame."""
    mids = []
    for f in steps:
        side = 1.0 if f.leg == "lleg" else -1.0
        mids.append((f.x + side * leg_offset_y_m * math.sin(f.yaw), f.y - side * leg_offset_y_m * math.cos(f.yaw),
                     f.yaw))
    out = []
    for a, b in zip(mids[:-1], mids[1:], strict=True):
        c, s = math.cos(a[2]), math.sin(a[2])
        out.append((c * (b[0] - a[0]) + s * (b[1] - a[1]), -s * (b[0] - a[0]) + c * (b[1] - a[1]), b[2] - a[2]))
    return out


@pytest.mark.slow
def test_a_velocity_change_mid_walk_takes_effect_within_two_steps(walker):
    w = walker
    gait = w.abc.gait
    changes = []

    def command(cmd, seconds):
        w.point.command = cmd
        changes.append(len(gait.footsteps) - len(gait.remaining_footsteps()))  # footstep being stepped on
        w.run(seconds)

    command(WalkCommand(0.1, 0.0, 0.0), 3.3)
    command(WalkCommand(0.0, 0.05, 0.0), 3.0)
    command(WalkCommand(0.0, 0.0, math.radians(5.0)), 3.0)
    strides = mid_strides(gait.footsteps)
    w.point.command = None
    w.walk_until_stopped(10.0)
    # footstep k is strides[k - 1]; the one stepped on at a change, c, and the next keep the old velocity at
    # worst: from c + 2 on the new one holds (hrpsys: re-planned at the mid-step check)
    sideways, turning = changes[1], changes[2]
    for k in range(sideways + 2, turning + 1):
        dx, dy, dth = strides[k - 1]
        assert abs(dx) < 1e-6 and dy > 0.02 and abs(dth) < 1e-6, (k, strides[k - 1])
    for k in range(turning + 2, len(strides)):
        dx, dy, dth = strides[k - 1]
        assert abs(dx) < 1e-6 and abs(dy) < 1e-6 and math.degrees(dth) == pytest.approx(5.0, abs=1e-6)
    assert turning - sideways >= 3  # (the windows above are not empty)
    # the simulated feet followed the plan: each sole within 3 cm / 2 deg of where the plan put it (measured
    # 2.1 cm, along x: the soles land ~2 cm ahead of the plan, as with plain goVelocity)
    for site, T in (("rleg_end", gait.T_world_rfoot), ("lleg_end", gait.T_world_lfoot)):
        pos, yaw = w.sole_truth(site)
        assert np.linalg.norm(pos[:2] - T[:2, 3]) < 0.03
        assert abs(math.degrees(yaw - math.atan2(T[1, 0], T[0, 0]))) < 2.0
    assert w.worst_deg < PLAIN_GO_VELOCITY_TILT_DEG + TILT_MARGIN_DEG


@pytest.mark.slow
def test_go_pos_during_a_go_pos_walk_ends_on_the_new_goal_relative_to_where_the_walk_began():
    w = Walker()
    ox, oy, oyaw = measured_mid(w)  # where the walk begins (the plan's origin is the controller's own)
    w.call(lambda: w.abc.go_pos(1.0, 0.0, 0.0))
    w.run(2.0)
    goal = (0.4, 0.2, math.radians(20.0))
    w.call(lambda: w.abc.go_pos(*goal))
    w.walk_until_stopped(20.0)
    x, y, yaw = measured_mid(w)
    c, s = math.cos(oyaw), math.sin(oyaw)
    gx, gy = ox + c * goal[0] - s * goal[1], oy + s * goal[0] + c * goal[1]
    # measured 1.8 cm (mostly the soles landing ahead of the plan) and 0.05 deg; bounds 2 cm / 2 deg (issue 10)
    assert math.hypot(x - gx, y - gy) < 0.02
    assert abs(math.degrees(yaw - oyaw - goal[2])) < 2.0
    assert w.worst_deg < MAX_TILT_DEG  # measured 0.73 deg


@pytest.mark.slow
def test_go_pos_during_a_walking_point_walk_replaces_it_and_ends_on_the_goal_relative_to_where_it_began(walker):
    w = walker
    ox, oy, oyaw = measured_mid(w)
    w.point.command = WalkCommand(0.1, 0.0, 0.0)  # the operator's stick, 3 s
    w.run(3.0)
    goal = (0.6, 0.1, math.radians(10.0))
    w.call(lambda: w.abc.go_pos(*goal))
    w.point.command = None  # the stick let go: the footsteps of goPos win anyway
    w.walk_until_stopped(20.0)
    x, y, yaw = measured_mid(w)
    c, s = math.cos(oyaw), math.sin(oyaw)
    gx, gy = ox + c * goal[0] - s * goal[1], oy + s * goal[0] + c * goal[1]
    err_m, err_deg = math.hypot(x - gx, y - gy), abs(math.degrees(yaw - oyaw - goal[2]))
    print(f"\ngoPos during a walking-point walk: {1e3 * err_m:.1f} mm, {err_deg:.2f} deg from the goal; "
          f"worst roll/pitch {w.worst_deg:.2f} deg")
    assert err_m < 0.02 and err_deg < 2.0  # issue 10's bounds
    assert w.worst_deg < MAX_TILT_DEG
