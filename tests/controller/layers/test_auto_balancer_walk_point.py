"""AutoBalancer and the walking point (Ports.walk_command): goVelocity every tick with the step parameters,
goStop when it goes to zero, ignored under the e-stop and the emergency walking stop (the layer alone)."""

import math

import numpy as np
import pytest

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.types import Ports, WalkCommand
from controller.kinematics.model import RobotKinematics
from controller.layers.auto_balancer import AutoBalancer
from controller.system import initial_reference
from controller.walking.auto_balancer_params import check_walk_command
from robot.generate import half_sitting_deg
from tests.controller.fakes import make_ctx

DT = 0.005
HALF_SITTING = np.deg2rad(half_sitting_deg())
FORWARD = WalkCommand(0.1, 0.0, 0.0)


class Ticker:
    """The AutoBalancer alone, ticked with a chosen walking point (and hold), on the half-sitting reference."""

    def __init__(self):
        kin = RobotKinematics()
        self.ref = initial_reference(kin, HALF_SITTING)
        self.abc = AutoBalancer(self.ref, DT, kinematics=kin)
        self.tick_no = 0
        self.run(2.1, None)  # blended in

    def run(self, seconds, command, hold=False, cp_flag=False):
        for _ in range(int(round(seconds / DT))):
            ctx = make_ctx(q=HALF_SITTING, t=self.tick_no * DT, tick=self.tick_no)
            ctx.last_ports = Ports(hold=hold, cp_flag=cp_flag)
            ctx.ports.walk_command = command
            self.abc.tick(ctx, self.ref)
            self.tick_no += 1
        return self.abc.status()


@pytest.fixture(scope="module")
def kin():
    return RobotKinematics()


def test_a_walk_command_walks_and_a_new_velocity_does_not_restart_the_gait():
    t = Ticker()
    assert t.run(0.1, FORWARD).walk_point == "walking"
    gait = t.abc.gait
    assert gait.walking and gait.velocity_mode == "walking"
    t.run(1.6, FORWARD)
    planned = gait.footsteps
    t.run(0.8, WalkCommand(0.0, 0.05, 0.0))
    # the same walk: the footsteps landed and the one being stepped on are kept, the later ones re-planned
    landed = len(planned) - len(gait.remaining_footsteps())
    assert gait.footsteps[:landed + 1] == planned[:landed + 1]
    def mid_y(steps):
        return 0.5 * (steps[-1].y + steps[-2].y)

    assert mid_y(gait.footsteps) > mid_y(planned) + 0.04  # sideways now, in the same walk


def test_the_step_parameters_reach_the_velocity_steps():
    t = Ticker()
    t.run(3.0, WalkCommand(0.2, 0.0, 0.0, max_stride_m=0.05, foot_distance_m=0.25))
    steps = t.abc.gait.footsteps
    assert steps[-1].x - steps[-2].x == pytest.approx(0.05, abs=1e-9)
    assert abs(steps[-1].y - steps[-2].y) == pytest.approx(0.25, abs=1e-9)


def test_zero_or_none_after_a_walk_it_drove_ends_it_as_go_stop_does():
    for stop in (WalkCommand(0.0, 0.0, 0.0), None):
        t = Ticker()
        t.run(1.5, FORWARD)
        assert t.run(0.01, stop).walk_point == "idle"
        assert t.abc.gait.velocity_mode == "ending"
        t.run(6.0, stop)
        gait = t.abc.gait
        assert not gait.walking
        Tr, Tl = gait.T_world_rfoot, gait.T_world_lfoot  # feet side by side
        assert Tr[0, 3] == pytest.approx(Tl[0, 3], abs=1e-9) and Tl[1, 3] - Tr[1, 3] == pytest.approx(0.19)


def test_an_idle_walking_point_leaves_a_go_velocity_walk_alone():
    t = Ticker()
    t.abc.go_velocity(0.1, 0.0, 0.0)
    t.run(2.0, None)
    assert t.abc.gait.velocity_mode == "walking"


def test_the_walking_point_is_ignored_while_a_footstep_list_is_walked():
    t = Ticker()
    t.abc.go_pos(0.2, 0.0, 0.0)
    status = t.run(0.5, FORWARD)
    assert status.walk_point.startswith("ignored: walking a footstep list")
    assert t.abc.gait.velocity_mode == "idle"


def test_after_the_emergency_walking_stop_it_needs_a_zero_before_it_walks_again():
    t = Ticker()
    t.run(1.5, FORWARD)
    t.abc.emergency_stop_walking()
    assert t.run(0.5, FORWARD).walk_point.startswith("ignored")
    t.run(6.0, FORWARD)
    gait = t.abc.gait
    assert not gait.walking  # stopped in place although the stick is still held
    assert "must read zero" in t.run(0.5, FORWARD).walk_point
    assert not gait.walking
    t.run(0.01, None)
    assert t.run(0.1, FORWARD).walk_point == "walking" and gait.walking


def test_under_the_hard_e_stop_it_is_ignored_and_needs_a_zero_after_the_release():
    t = Ticker()
    status = t.run(0.5, FORWARD, hold=True)
    assert status.walk_point == "ignored: the hard e-stop holds" and not t.abc.gait.walking
    assert "must read zero" in t.run(0.5, FORWARD).walk_point
    t.run(0.01, WalkCommand(0.0, 0.0, 0.0))
    assert t.run(0.1, FORWARD).walk_point == "walking"


def test_an_invalid_command_is_ignored_in_the_loop_and_refused_by_the_check_naming_the_field():
    bad = WalkCommand(0.1, 0.0, 0.0, foot_distance_m=0.5)
    t = Ticker()
    assert t.run(0.1, bad).walk_point.startswith("ignored: out of range")
    assert not t.abc.gait.walking
    with pytest.raises(InvalidCommand, match=r"walk\.foot_distance_m=0\.5 \[m\]; allowed: \[0\.14, 0\.3\]"):
        check_walk_command(bad)
    with pytest.raises(InvalidCommand, match=r"walk\.vtheta_rad_s"):
        check_walk_command(WalkCommand(0.0, 0.0, math.inf))
    with pytest.raises(InvalidCommand, match=r"walk\.max_stride_m"):
        check_walk_command(WalkCommand(0.1, 0.0, 0.0, max_stride_m=-0.1))
    check_walk_command(WalkCommand(0.1, 0.0, 0.0, max_stride_m=0.1, foot_distance_m=0.2))


def test_no_walk_starts_while_the_cp_flag_is_up_and_a_held_stick_must_read_zero_after_it():
    # campaign seed 1009: a walk started while the flag was still up (the robot off balance) fell
    t = Ticker()
    status = t.run(0.2, FORWARD, cp_flag=True)
    assert not t.abc.gait.walking and "capture-point flag is up" in status.walk_point
    for verb in (lambda: t.abc.go_pos(0.2, 0.0, 0.0), lambda: t.abc.go_velocity(0.1, 0.0, 0.0)):
        with pytest.raises(InvalidState, match="capture-point flag is up"):
            verb()
    assert "read zero" in t.run(0.5, FORWARD).walk_point and not t.abc.gait.walking  # the flag down, stick held
    t.run(0.05, None)
    assert t.run(0.1, FORWARD).walk_point == "walking" and t.abc.gait.walking


@pytest.mark.parametrize("roll_deg, walks", [(0.0, True), (4.0, True), (-4.0, True), (12.0, False), (-12.0, False)])
def test_a_walk_starts_only_with_the_leg_range_walking_needs_left(roll_deg, walks):
    # campaign seeds 1017, 1018: the waist rolled until a hip roll sat at its limit; a walk then fell
    t = Ticker()
    t.ref = t.ref.with_(base_rpy_rad=np.array((math.radians(roll_deg), 0.0, 0.0)))
    t.run(0.5, None)
    if walks:
        t.abc.go_velocity(0.1, 0.0, 0.0)
        assert t.abc.gait.walking
        return
    with pytest.raises(InvalidState, match=r"LEG_JOINT1 is .* deg from its limit .* walking needs 12 deg"):
        t.abc.go_velocity(0.1, 0.0, 0.0)
    assert "straighten the waist" in t.run(0.1, FORWARD).walk_point and not t.abc.gait.walking


@pytest.mark.parametrize("verb", ["go_velocity", "go_pos"])
def test_walk_verbs_under_the_emergency_walking_stop_are_refused_and_leave_it_in_force(verb):
    # campaign seed 1012: a goVelocity refused (a footstep list walked) had cleared the stop: the walk went on
    t = Ticker()
    t.abc.go_pos(1.0, 0.0, 0.0)
    t.run(1.5, None)
    t.abc.emergency_stop_walking()
    assert t.abc.walking_stop
    with pytest.raises(InvalidState, match="emergency walking stop is in force"):
        getattr(t.abc, verb)(0.1, 0.0, 0.0)
    assert t.abc.walking_stop
    t.run(6.0, None)
    assert not t.abc.gait.walking and not t.abc.walking_stop  # it ended in place
    getattr(t.abc, verb)(0.1, 0.0, 0.0)  # and the robot walks again
    assert t.abc.gait.walking
