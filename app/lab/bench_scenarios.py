"""The benchmark's robot scenarios: what the robot does while the chain is timed (`bench --scenario`), shared by the
chain's bench (app.lab.bench) and the recording's (app.lab.bench_recording)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.service import OperatorService
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint
from robot.generate import half_sitting_deg
from robot.names import JOINT_NAMES


@dataclass(frozen=True)
class Scenario:
    """What the robot does during a benchmark: `setup(loop)` queues its commands before the first timed
    tick, after `warmup_s` of untimed standing (the AutoBalancer and the Stabilizer blend in)."""

    description: str
    setup: Callable[[OperatorService], None]
    warmup_s: float = 0.0
    needs: tuple[str, ...] = ()  # layers the scenario commands
    #: called with the robot at every tick boundary of the timed part (streamed setpoints), not timed
    stream: Callable[[LocalRobot], None] | None = None
    #: (label, predicate on the snapshot after each timed tick, not timed): the report adds the tick's and the
    #: layers' figures over the ticks it holds for under that label, and over the others under "other"
    watch: tuple[str, Callable[[Any], bool]] | None = None


def _stand(service: OperatorService) -> None:
    """Nothing to send: the chain holds the half-sitting posture it started in."""


def _arms(service: OperatorService) -> None:
    """Both arms forward with the elbows bent and back, over and over (setJointAngles sequence)."""
    half_sitting = np.array(half_sitting_deg(), dtype=float)
    q_fwd = half_sitting.copy()
    for name, deg in (("RARM_JOINT0", -50), ("RARM_JOINT3", -70), ("LARM_JOINT0", -50), ("LARM_JOINT3", -70)):
        q_fwd[JOINT_NAMES.index(name)] = deg
    poses = [np.deg2rad(q_fwd), np.deg2rad(half_sitting)] * 30
    service.set_joint_angles_sequence(poses, [1.5] * len(poses))


def _walk(service: OperatorService) -> None:
    """goVelocity(0.1 m/s forward) for the whole timed part (the AutoBalancer is running by then)."""
    service.go_velocity(0.1, 0.0, 0.0)


def _teleop_walk(service: OperatorService) -> None:
    """Nothing to set up: the walking point streamed by `_teleop_stream` drives the AutoBalancer."""


def _teleop_stream(robot: LocalRobot) -> None:
    """Both hands on slow circles (0.05 m/s) and the head sweeping (20 deg/s), with the walk point at 0.1 m/s:
    one setpoint table every tick, applied at the boundary as the robot applies the operator's stream."""
    t = robot.plant.time_s
    c, s_ = math.cos(1.0 * t), math.sin(1.0 * t)
    still = (0.0, 0.0, 0.0)
    robot.host.apply_setpoints({
        "rhand": Setpoint("rhand", (0.05 * c, 0.0, 0.05 * s_), still),
        "lhand": Setpoint("lhand", (0.05 * c, 0.0, -0.05 * s_), still),
        "head": Setpoint("head", still, (0.0, 0.0, math.radians(20.0) * c)),
        "walk": Setpoint("walk", (0.1, 0.0, 0.0), still),
    }, t)


def _teleop_hand_stream(robot: LocalRobot) -> None:
    """Standing, the right hand on a slow circle (0.05 m/s) in x-z, the left hand's and the head's as in 'teleop'."""
    _teleop_standing(robot, "rhand")


def _teleop_foot_stream(robot: LocalRobot) -> None:
    """Standing, the right foot instead of the right hand: up first (the COM goes over the left foot, 1.6 s),
    then on a slow ellipse (0.05 m/s across, 0.02 m/s up and down) in x-z; the left hand's and the head's as in
    'teleop'."""
    _teleop_standing(robot, "rfoot")


def _teleop_standing(robot: LocalRobot, point: str) -> None:
    t = robot.plant.time_s
    c, s_ = math.cos(1.0 * t), math.sin(1.0 * t)
    still = (0.0, 0.0, 0.0)
    up = point == "rfoot" and t < TELEOP_WARMUP_S + 2.5  # (the foot point waits 1.6 s for the COM to shift)
    robot.host.apply_setpoints({
        point: Setpoint(point, (0.0, 0.0, 0.05) if up else (0.05 * c, 0.0, (0.02 if point == "rfoot" else 0.05) * s_),
                        still),
        "lhand": Setpoint("lhand", (0.05 * c, 0.0, -0.05 * s_), still),
        "head": Setpoint("head", still, (0.0, 0.0, math.radians(20.0) * c)),
    }, t)


TELEOP_WARMUP_S = 2.5  # [s] standing before the timed part of the teleop scenarios

# the catch: the push map's run 0.1 m/s, 20 N s from 135 deg at phase 0.6875 (app.lab.study.push_walking), one gait
# cycle earlier; the walk goes straight ahead, so the direction in the robot's frame is the world's
CATCH_WALK_START_S = 2.5  # [s] the warm-up's end: goVelocity
CATCH_PUSH_AFTER_S = 3.275  # [s] after goVelocity: late in the left foot's swing, the capture step follows
CATCH_PUSH = ("BODY", 20.0, 135.0, 0.1)  # body, impulse [N s], direction [deg], duration [s]


def _catch_push(robot: LocalRobot) -> None:
    """The push, once, at CATCH_PUSH_AFTER_S into the walk (the simulator's operation, as the push map's)."""
    from app.service.verbs import Push

    t_push = CATCH_WALK_START_S + CATCH_PUSH_AFTER_S
    if abs(robot.plant.time_s - t_push) < 0.5 * robot.loop.dt_control_s:
        body, impulse_ns, direction_deg, duration_s = CATCH_PUSH
        yaw = math.radians(direction_deg)
        force = (impulse_ns / duration_s * math.cos(yaw), impulse_ns / duration_s * math.sin(yaw), 0.0)
        robot.submit(Push(body, force, duration_s)).result()


def _catching(snapshot) -> bool:
    return bool(snapshot.layers["abc"].emergency_step)


#: Benchmark scenarios by name.
SCENARIOS: dict[str, Scenario] = {
    "stand": Scenario("hold half-sitting", _stand),
    "arms": Scenario("arms forward and back with setJointAngles (SequencePlayer interpolating)", _arms,
                     needs=("seq",)),
    "walk": Scenario("goVelocity(0.1 m/s, 0, 0) after 2.5 s of standing (not timed)", _walk, warmup_s=2.5,
                     needs=("abc",)),
    "teleop": Scenario("walk at 0.1 m/s through the operation layer's walking point while both hands and the "
                       "head are streamed through it every tick, after 2.5 s of standing", _teleop_walk,
                       warmup_s=2.5, needs=("op", "abc"), stream=_teleop_stream),
    "teleop_hand": Scenario("standing, the right hand, the left hand and the head streamed through the operation "
                            "layer every tick (the reference for teleop_foot)", _teleop_walk,
                            warmup_s=TELEOP_WARMUP_S, needs=("op", "abc"), stream=_teleop_hand_stream),
    "teleop_foot": Scenario("as teleop_hand with the right foot streamed instead of the right hand: the COM over "
                            "the left foot, the sole lifted and moved on a circle", _teleop_walk,
                            warmup_s=TELEOP_WARMUP_S, needs=("op", "abc"), stream=_teleop_foot_stream),
    "catch": Scenario(f"goVelocity(0.1 m/s) as 'walk', pushed {CATCH_PUSH_AFTER_S:g} s into the walk "
                      f"({CATCH_PUSH[1]:g} N s from {CATCH_PUSH[2]:g} deg, late in a swing): the capture step; "
                      "'catching' reports the ticks the emergency step is up (--duration 8 covers it whole)",
                      _walk, warmup_s=CATCH_WALK_START_S, needs=("abc", "st"), stream=_catch_push,
                      watch=("catching", _catching)),
}
