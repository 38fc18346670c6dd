"""The chain order and the fixed-rate loop: queue at tick boundaries, faults, pacing."""

import time
from dataclasses import dataclass

import numpy as np
import pytest

from controller.core.chain import CHAIN_ORDER, Chain
from controller.core.errors import InvalidCommand
from controller.core.layer import Layer, Status
from controller.core.loop import ControlLoop
from controller.core.types import Reference
from tests.controller.fakes import make_sensors


class FakePlant:
    """A plant whose joints follow the command after one physics step; time advances per step."""

    dt_physics = 0.001

    def __init__(self):
        self.t = 0.0
        self.q = np.zeros(30)
        self.q_cmd = np.zeros(30)
        self.writes = []

    def read(self):
        return make_sensors(q=self.q.copy(), t=self.t)

    def write(self, q):
        self.q_cmd = np.array(q)
        self.writes.append(self.q_cmd)

    @property
    def time_s(self):
        return self.t

    def step(self, n=1):
        self.t += n * self.dt_physics
        self.q = self.q_cmd.copy()


class Ramp(Layer):
    """Source layer: joint 0 grows by `rate` rad per tick; can be told to fail."""

    name = "seq"

    def __init__(self, rate=0.001):
        super().__init__()
        self.x = 0.0
        self.rate = rate
        self.fail = False

    def tick(self, ctx, ref):
        if self.fail:
            raise RuntimeError("boom")
        self.x += self.rate
        q = np.zeros(30)
        q[0] = self.x
        return ref.with_(q_rad=q)


@dataclass(frozen=True, slots=True)
class FreezeStatus(Status):
    engaged: bool
    reason: str | None


class Freeze(Layer):
    name = "hes"
    safe_stop = True  # the loop engages it on a fault

    def __init__(self):
        super().__init__()
        self.engaged = False
        self.reason = None
        self.q = None

    def engage(self, q=None, reason="operator"):
        self.engaged, self.q, self.reason = True, q, reason

    def tick(self, ctx, ref):
        ctx.ports.hold = self.engaged
        return ref.with_(q_rad=self.q) if self.engaged else ref

    def status(self):
        return FreezeStatus(enabled=True, engaged=self.engaged, reason=self.reason)


def make_loop(**kw):
    plant = FakePlant()
    layers = {}

    def factory(sensors, dt):
        layers["seq"], layers["hes"] = Ramp(), Freeze()
        return Chain({"hes": layers["hes"], "seq": layers["seq"]})

    return ControlLoop(plant, factory, dt_control_s=0.005, **kw), plant, layers


def test_chain_runs_layers_in_the_declared_order_whatever_the_mapping_order():
    chain = Chain({"hes": Freeze(), "seq": Ramp()})
    assert chain.order() == ["seq", "hes"]
    assert chain.describe() == "seq -> hes"
    assert CHAIN_ORDER == ("kf", "rmfo", "seq", "op", "es", "ic", "abc", "st", "co", "hes", "el")


def test_chain_rejects_unknown_layer_names_listing_the_valid_ones():
    with pytest.raises(InvalidCommand, match="kf"):
        Chain({"xyz": Ramp()})


def test_loop_steps_physics_by_whole_control_periods():
    loop, plant, _ = make_loop()
    loop.run_for(1.0)
    assert loop.tick_count == 200
    assert plant.t == pytest.approx(1.0)
    assert loop.substeps == 5


def test_control_period_must_be_a_multiple_of_the_physics_step():
    with pytest.raises(InvalidCommand, match="multiple"):
        ControlLoop(FakePlant(), lambda s, dt: Chain({}), dt_control_s=0.0045)


def test_commands_run_between_ticks_and_return_results_or_errors():
    loop, _, layers = make_loop()
    assert loop.call(lambda: 42) == 42
    with pytest.raises(ZeroDivisionError):
        loop.call(lambda: 1 / 0)
    loop.run_for(0.1)  # the loop survives a failing command
    assert loop.tick_count == 20


def test_a_failing_layer_is_a_reported_fault_that_holds_the_command_and_engages_the_estop():
    loop, plant, layers = make_loop()
    loop.run_for(0.05)
    held = plant.writes[-1].copy()
    layers["seq"].fail = True
    snap = loop.run_for(0.05)
    assert snap.fault is not None and "boom" in snap.fault
    assert snap.safety.hard_stop is True
    assert np.array_equal(plant.writes[-1], held)
    layers["seq"].fail = False
    loop.clear_fault()
    snap = loop.run_for(0.05)
    assert snap.fault is None
    assert np.array_equal(plant.writes[-1], held)  # still frozen until the operator releases


def test_snapshots_are_immutable():
    loop, _, _ = make_loop()
    snap = loop.run_for(0.01)
    with pytest.raises(ValueError):
        snap.q_cmd_rad[0] = 1.0
    with pytest.raises(AttributeError):
        snap.time_s = 3.0


def test_paced_and_unpaced_runs_give_the_same_trajectory():
    fast, fast_plant, _ = make_loop()
    fast.run_for(0.5)
    paced, paced_plant, _ = make_loop()
    paced.start(speed=5.0)
    t0 = time.perf_counter()
    while paced.tick_count < 100 and time.perf_counter() - t0 < 10:
        time.sleep(0.01)
    paced.stop()
    n = 100
    assert paced.tick_count >= n
    assert np.array_equal(np.array(paced_plant.writes[:n]), np.array(fast_plant.writes[:n]))
    # pacing: 100 ticks = 0.5 s of sim time took about 0.1 s of wall time at 5x
    assert paced.tick_count < 400


def test_reference_from_arrays_validates_shapes():
    with pytest.raises(ValueError):
        Reference.from_arrays(np.zeros(29))


def test_before_tick_runs_with_the_control_time_after_the_commands_of_that_boundary():
    seen = []
    loop, plant, _ = make_loop(before_tick=lambda t: seen.append(("tick", t)))
    loop.step()
    loop.submit(lambda: seen.append(("command", plant.time_s)))  # not running: applied at once
    loop.step()
    assert seen == [("tick", 0.0), ("command", 0.005), ("tick", 0.005)]


def test_an_exception_in_before_tick_never_stops_the_loop():
    def boom(t):
        raise RuntimeError("behaviour bug")

    loop, plant, _ = make_loop(before_tick=boom)
    for _ in range(3):
        loop.step()
    assert loop.tick_count == 3 and loop.fault is None


def test_pacing_is_true_while_run_paced_ticks_in_the_callers_own_thread():
    """The robot process runs run_paced in its main thread (no background thread: `running` stays false);
    `pacing` says a tick boundary must not wait for work done elsewhere (a camera's result)."""
    loop, _, _ = make_loop()
    loop.speed = None
    seen = []

    def between_ticks():
        seen.append((loop.pacing, loop.running))
        if len(seen) == 3:
            loop.request_stop()

    assert not loop.pacing
    loop.run_paced(between_ticks=between_ticks)
    assert seen == [(True, False)] * 3 and not loop.pacing


def test_a_reset_starts_a_new_schedule_and_the_timing_figures_of_the_new_run_only():
    """Reset at a tick boundary after 0.5 s paced at real time: the first tick of the new run is not measured
    against the old schedule (it was the whole old run late), and the figures cover the new run only."""
    loop, _, _ = make_loop()
    loop.speed = 1.0
    boundaries = []

    def between_ticks():
        boundaries.append(loop.snapshot.time_s)
        if len(boundaries) == 100:  # 0.5 s of the first run
            loop.replace_plant(FakePlant())
        elif len(boundaries) == 121:
            loop.request_stop()

    loop.run_paced(between_ticks=between_ticks)
    t = loop.timing()
    assert t.ticks == 21  # boundaries 101..121: the new run's ticks (the reset was at boundary 100)
    assert t.lateness_max_ms < 50.0, t
    assert t.speed_run is not None and 0.5 < t.speed_run < 1.5, t


class Prepare(Layer):
    """A layer with after-write work: records when it ran (the plant's writes so far) and on which ports."""

    name = "abc"

    def __init__(self, plant):
        super().__init__()
        self.plant = plant
        self.calls = []  # (writes seen, the ports given)
        self.fail = False

    def tick(self, ctx, ref):
        return ref

    def after_write(self, ports):
        if self.fail:
            raise RuntimeError("prepare failed")
        self.calls.append((len(self.plant.writes), ports))


def make_loop_with_prepare():
    plant = FakePlant()
    layers = {}

    def factory(sensors, dt):
        layers["seq"], layers["abc"], layers["hes"] = Ramp(), Prepare(plant), Freeze()
        return Chain(dict(layers))

    return ControlLoop(plant, factory, dt_control_s=0.005), plant, layers


def test_after_write_runs_once_per_tick_after_the_command_is_written_on_the_ports_the_next_tick_reads():
    loop, plant, layers = make_loop_with_prepare()
    seen = []
    layers["seq"].tick = lambda ctx, ref: seen.append(ctx.last_ports) or Ramp.tick(layers["seq"], ctx, ref)
    loop.run_for(0.02)
    calls = layers["abc"].calls
    assert [w for w, _ in calls] == [1, 2, 3, 4]  # each tick's command was out before its after-write work
    assert [p for _, p in calls[:-1]] == seen[1:]  # the ports it was given are the next tick's last_ports
    assert all(a is b for (_, a), b in zip(calls[:-1], seen[1:], strict=True))
    assert loop.after_write_timer.percentiles()["n"] == 4 and loop.read_to_write_timer.percentiles()["n"] == 4
    assert loop.chain.after_write_timers.keys() == {"abc"}  # only the layers that have after-write work


def test_after_write_is_not_called_for_a_disabled_layer_nor_after_a_faulted_tick():
    loop, plant, layers = make_loop_with_prepare()
    layers["abc"].enabled = False
    loop.run_for(0.02)
    assert layers["abc"].calls == []
    layers["abc"].enabled = True
    layers["seq"].fail = True
    loop.run_for(0.02)
    assert loop.fault is not None and layers["abc"].calls == []


def test_an_exception_in_after_write_is_a_fault_the_loop_survives_with_the_command_written_held():
    loop, plant, layers = make_loop_with_prepare()
    loop.run_for(0.02)
    layers["abc"].fail = True
    loop.step()
    written = plant.writes[-1].copy()  # the tick's command went out before its after-write work failed
    assert loop.fault is not None and "prepare failed" in loop.fault
    assert loop.hard_stop_engaged and np.array_equal(layers["hes"].q, written)
    assert loop._ports.hold  # the next tick's layers before hes hold, as after a faulted tick
    snap = loop.run_for(0.02)
    assert snap.safety.hard_stop and np.array_equal(plant.writes[-1], written)
