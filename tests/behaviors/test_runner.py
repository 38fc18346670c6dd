"""BehaviorRunner (unit, against a fake operation layer): ids and states, the behaviours' sum per point,
one owner per point, the 50 % overrun rule, and zero velocity left behind by a cancel or a failure."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from behaviors.base import Behavior, BehaviorParams, Context, Output
from behaviors.runner import BehaviorRunner, LatchedStop
from controller.core.errors import InvalidCommand, InvalidState, UnknownName
from controller.core.types import WalkCommand
from controller.operation.points import Twist
from tests.behaviors.fakes import harness


@dataclass(frozen=True)
class PushParams(BehaviorParams):
    point: str = field(default="rhand", metadata={"unit": "-", "choices": ("rhand", "lhand", "waist", "walk")})
    speed_m_s: float = field(default=0.1, metadata={"unit": "m/s", "min": -0.5, "max": 0.5})
    duration_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.0, "max": 100.0})
    finish_after_s: float = field(default=-1.0, metadata={"unit": "s", "doc": "< 0: never finishes by itself"})
    explode_after_s: float = field(default=-1.0, metadata={"unit": "s"})


class Push(Behavior):
    """Moves one point at a constant speed (z for the waist, x otherwise)."""

    name = "push"
    Params = PushParams

    def __init__(self, params=None) -> None:
        super().__init__(params)
        self.stopped = self.torn_down = False

    def points(self):
        return (self.params.point,)

    def nominal_duration_s(self) -> float:
        return self.params.duration_s

    def step(self, ctx: Context) -> Output:
        p = self.params
        if 0 <= p.finish_after_s <= ctx.elapsed_s:
            return self.succeed("done", elapsed_s=ctx.elapsed_s)
        if 0 <= p.explode_after_s <= ctx.elapsed_s:
            raise RuntimeError("boom")
        if p.point == "walk":
            return Output({"walk": Twist.of((p.speed_m_s, 0, 0))}, WalkCommand(p.speed_m_s, 0.0, 0.0))
        lin = (0, 0, p.speed_m_s) if p.point == "waist" else (p.speed_m_s, 0, 0)
        return Output({p.point: Twist.of(lin)})

    def stop(self, ctx):
        self.stopped = True

    def teardown(self, ctx):
        self.torn_down = True


def test_a_run_gets_an_id_and_runs_until_it_succeeds():
    h = harness()
    b = Push(PushParams(finish_after_s=0.5))
    rid = h.runner.run(b)
    assert h.runner.get(rid).state == "running"
    status = h.run_until_done(rid)
    assert status.state == "succeeded" and status.progress == 1.0 and status.message == "done"
    assert status.result["elapsed_s"] == pytest.approx(0.5, abs=0.006)
    assert b.torn_down and not b.stopped  # a run that ends by itself is not interrupted


def test_twists_of_two_runs_on_different_points_are_both_handed_to_the_op_layer():
    h = harness()
    h.runner.run(Push(PushParams(point="rhand", speed_m_s=0.1)))
    h.runner.run(Push(PushParams(point="lhand", speed_m_s=-0.05)))
    h.tick()
    twists, walk = h.op.calls[-1]
    assert twists["rhand"].linear_m_s.tolist() == [0.1, 0, 0]
    assert twists["lhand"].linear_m_s.tolist() == [-0.05, 0, 0]
    assert walk is None


def test_a_second_run_on_a_driven_point_is_refused_naming_the_running_one():
    h = harness()
    first = h.runner.run(Push())
    with pytest.raises(InvalidState, match=rf"run {first} \(push\)"):
        h.runner.run(Push())


def test_progress_is_elapsed_over_nominal_time():
    h = harness()
    rid = h.runner.run(Push(PushParams(duration_s=1.0)))
    h.tick(101)
    assert h.runner.get(rid).progress == pytest.approx(0.5, abs=0.01)


def test_a_run_fails_when_it_overruns_its_nominal_duration_by_half_and_leaves_zero_velocity():
    h = harness()
    b = Push(PushParams(duration_s=1.0))
    rid = h.runner.run(b)
    status = h.run_until_done(rid, timeout_s=5.0)
    assert status.state == "failed" and "50 %" in status.message
    assert status.ended_s == pytest.approx(1.5, abs=0.011)
    assert b.stopped and b.torn_down
    n = len(h.op.calls)
    h.tick(10)
    assert len(h.op.calls) == n  # nothing handed over any more: the op layer's behaviour part is zero
    assert h.op.pending == ({}, None)


def test_a_cancelled_run_leaves_zero_velocity_behind():
    h = harness()
    rid = h.runner.run(Push())
    h.tick(20)
    x_before = h.op.p["rhand"][0]
    status = h.runner.cancel(rid)
    assert status.state == "cancelled"
    assert status.to_dict()["cause"] == "cancel"  # named from the closed set (behaviors.causes), for the page
    h.tick(20)
    assert h.op.p["rhand"][0] == x_before


def test_a_cancelled_velocity_walk_is_followed_by_one_zero_walk_command():
    h = harness()
    rid = h.runner.run(Push(PushParams(point="walk", speed_m_s=0.1)))
    h.tick(3)
    assert h.op.calls[-1][1] == WalkCommand(0.1, 0.0, 0.0)
    h.runner.cancel(rid)
    h.tick(3)
    assert h.op.calls[-1] == ({}, WalkCommand(0.0, 0.0, 0.0))


def test_an_exception_in_a_behaviour_fails_its_run_and_not_the_others():
    h = harness()
    bad = h.runner.run(Push(PushParams(point="rhand", explode_after_s=0.1)))
    good = h.runner.run(Push(PushParams(point="lhand")))
    h.tick(40)
    assert h.runner.get(bad).state == "failed" and "boom" in h.runner.get(bad).message
    assert h.runner.get(bad).to_dict()["cause"] is None  # an exception names no cause of the closed set
    assert h.runner.get(good).to_dict()["cause"] is None  # running: no cause
    assert h.runner.get(good).state == "running"
    assert "rhand" not in h.op.calls[-1][0]


def test_a_twist_on_an_unclaimed_point_fails_the_run():
    class Sneaky(Push):
        def step(self, ctx):
            return Output({"lhand": Twist.of((0.1, 0, 0))})

    h = harness()
    rid = h.runner.run(Sneaky())
    h.tick()
    assert h.runner.get(rid).state == "failed" and "did not claim" in h.runner.get(rid).message


def test_a_twist_the_point_does_not_take_fails_the_run():
    h = harness()
    rid = h.runner.run(Push(PushParams(point="walk")))
    h.runner._running[rid].behavior.step = lambda ctx: Output({"walk": Twist.of((0, 0, 0.1))})
    h.tick()
    assert h.runner.get(rid).state == "failed" and "walk.linear.z" in h.runner.get(rid).message


def test_unknown_run_ids_name_the_known_ones():
    h = harness()
    rid = h.runner.run(Push(PushParams(finish_after_s=0.0)))
    h.tick()
    with pytest.raises(UnknownName, match=rf"runs: \[{rid}\]"):
        h.runner.get(99)
    assert h.runner.cancel(rid).state == "succeeded"  # cancelling a finished run changes nothing


def test_a_behaviour_that_needs_points_is_refused_without_an_operation_layer():
    runner = BehaviorRunner(lambda: None, commands=None, dt_s=0.005)
    with pytest.raises(InvalidCommand, match="no operation layer"):
        runner.run(Push())


def test_a_start_that_raises_refuses_the_run_and_takes_no_id():
    class Refused(Push):
        def start(self, ctx):
            raise InvalidState("not now")

    h = harness()
    with pytest.raises(InvalidState, match="not now"):
        h.runner.run(Refused())
    assert h.runner.ids() == []
    assert h.runner.run(Push()) == 1


def test_the_same_runs_give_the_same_trajectory():
    def trajectory():
        h = harness()
        h.runner.run(Push(PushParams(speed_m_s=0.07, finish_after_s=0.8)))
        h.tick(200)
        return h.op.p["rhand"].copy()

    np.testing.assert_array_equal(trajectory(), trajectory())


MOTION_STOP = LatchedStop("motion_stop", "capture_point", 1.234, "the motion stop, raised by the CP flag at 1.234 s")
WALKING_STOP = LatchedStop("walking_stop", "operator", 2.0, "the walking stop, raised by the operator", ("walk",))


def test_a_run_is_refused_under_a_latched_stop_naming_it():
    h = harness(stops=lambda: (MOTION_STOP,))
    with pytest.raises(InvalidState, match="push refused: the motion stop, raised by the CP flag at 1.234 s"):
        h.runner.run(Push())
    assert h.runner.ids() == []


def test_a_running_run_a_stop_latches_on_ends_failed_naming_the_stop_and_leaves_nothing_moving():
    latched: list[LatchedStop] = []
    h = harness(stops=lambda: tuple(latched))
    b = Push()
    rid = h.runner.run(b)
    h.tick(10)
    latched.append(MOTION_STOP)
    h.tick()
    status = h.runner.get(rid)
    assert status.state == "failed" and b.stopped and b.torn_down
    assert status.message == (f"push stopped at t = {status.ended_s:.3f} s: the motion stop, raised by the CP flag "
                              "at 1.234 s")


def test_a_stop_ends_only_the_runs_that_need_what_it_stops():
    latched: list[LatchedStop] = []
    h = harness(stops=lambda: tuple(latched))
    walker, hand = h.runner.run(Push(PushParams(point="walk"))), h.runner.run(Push(PushParams(point="rhand")))
    h.tick(5)
    latched.append(WALKING_STOP)
    h.tick()
    assert h.runner.get(walker).state == "failed" and "the walking stop" in h.runner.get(walker).message
    assert h.runner.get(hand).state == "running"
