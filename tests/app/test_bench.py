"""The bench's labels say what ran: a disabled layer that kept working is in the chain, not a pass-through."""

import numpy as np

from app.lab.bench import layers_that_ran, run_bench
from app.service import OperatorService
from app.service.local import LocalRobot
from robot.names import joint_index

RARM0 = joint_index("RARM_JOINT0")


def test_disabled_layers_that_still_work_are_labelled_as_run_and_only_the_others_as_passthrough():
    r = run_bench("stand", 0.05, layers="seq")
    # kf, rmfo and hes ignore enabled = False (the estimate, the e-stop); the old labels put them with the
    # pass-through layers and the chain was "seq"
    assert r["chain"] == "kf -> rmfo -> seq -> hes"
    assert r["disabled_but_ran"] == ["kf", "rmfo", "hes"]
    assert list(r["passthrough"]) == ["op", "es", "ic", "abc", "st", "co", "el"]
    assert list(r["layers"]) == ["kf", "rmfo", "seq", "hes"]
    r = run_bench("stand", 0.05, layers="foundation")  # kf and hes asked for: nothing disabled ran
    assert r["chain"] == "kf -> rmfo -> seq -> co -> hes -> el" and r["disabled_but_ran"] == []
    assert list(r["passthrough"]) == ["op", "es", "ic", "abc", "st"]


def test_what_the_probe_calls_run_does_run_when_disabled():
    robot = LocalRobot(speed=None)
    loop, chain = robot.loop, robot.chain
    service = OperatorService(robot)
    service.enable_layers({name: False for name in chain.order() if name != "seq"})
    updates = []
    kf_filter = chain["kf"].filter
    update = kf_filter.update
    kf_filter.update = lambda *a: updates.append(1) or update(*a)
    assert layers_that_ran(loop, ticks=10) == {"seq", "kf", "rmfo", "hes"}  # seq enabled, the others not
    assert len(updates) == 10  # the KalmanFilter updated its estimate every tick, disabled
    assert np.any(np.asarray(loop.snapshot.wrenches_ext) != 0.0)  # the RemoveForceOffset's feet wrenches
    # the HardEmergencyStopper, disabled, still freezes the command in the middle of a 0.5 s move
    q_goal = np.array(loop.snapshot.q_seq_rad)
    q_goal[RARM0] = np.deg2rad(-30.0)
    service.set_joint_angles(q_goal, 0.5)
    robot.run_for(0.1)
    moving = np.array(loop.snapshot.q_cmd_rad)
    robot.step()
    assert loop.snapshot.q_cmd_rad[RARM0] < moving[RARM0]  # the move is under way
    robot.estop()
    robot.step()
    frozen = np.array(loop.snapshot.q_cmd_rad)
    robot.run_for(0.2)
    assert loop.snapshot.safety.hard_stop is True
    np.testing.assert_array_equal(loop.snapshot.q_cmd_rad, frozen)


def test_the_record_scenario_reports_what_recording_adds_to_a_tick():
    r = run_bench("record", 0.25)
    assert r["scenario"] == "record" and r["error"] is None and not r["fallen"]
    # the figure itself is measured by hand (docs/measurements/speed.md), not asserted
    assert 0 < r["recording_per_tick_ms"] < 1.0
    assert r["recorder_tick_cpu_us"]["n"] == 50 and r["recorder_inputs_cpu_us"]["n"] == 50  # an input every tick
    assert r["file_bytes_per_sim_s"] > 0 and r["tick_cpu_with_us"]["n"] == r["tick_cpu_without_us"]["n"] == 50
    assert len(r["recording_per_tick_ms_each_round"]) == r["rounds"] == 2


def test_the_catch_scenario_pushes_the_walk_and_reports_the_ticks_of_the_capture_step_apart():
    report = run_bench("catch", duration_s=4.0)
    assert not report["fallen"]
    catching, other = report["catching"], report["other"]
    assert catching["ticks"] > 100 and catching["ticks"] + other["ticks"] == report["ticks"]
    assert set(catching["layers"]) == set(report["layers"]) and "p99_ms" in catching["layers"]["abc"]
    # the tick split at the write: the catch's re-plan runs once the command is out, reported apart from what the
    # command waits for
    assert catching["after_write_ms"]["p99_ms"] > 0.0 and set(report["after_write_layers"]) == {"abc"}
    for part in (report, catching, other):
        assert part["read_to_write_ms"]["p50_ms"] < part["tick_ms"]["p50_ms"]

