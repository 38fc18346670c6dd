"""Runtime: commands and resets while the loop thread runs, and the run statistics."""

import time

import pytest

from app.runtime import Runtime, jsonable


def wait_for(predicate, timeout_s=10.0):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached in time"
        time.sleep(0.005)


def test_commands_and_a_reset_go_through_while_the_loop_thread_runs():
    rt = Runtime(speed=None)
    rt.start()
    try:
        wait_for(lambda: rt.loop.snapshot.time_s > 0.2)
        rt.call(lambda: rt.loop.chain["hes"].engage())
        wait_for(lambda: rt.state()["emergency"]["hard_stop"])  # seen from the next snapshot on
        rt.reset()
        assert rt.running
        assert rt.state()["emergency"]["hard_stop"] is False
        assert rt.loop.snapshot.time_s < 0.2
        wait_for(lambda: rt.loop.snapshot.time_s > 0.3)
    finally:
        rt.stop()
    assert not rt.running
    assert rt.stats.ticks > 40 and rt.stats.faults == set() and rt.stats.fallen is False


def test_an_unknown_scene_is_rejected_listing_the_available_ones():
    with pytest.raises(ValueError, match="default"):
        Runtime(scene="mars")


def test_jsonable_turns_numpy_and_non_finite_values_into_plain_json():
    import numpy as np

    assert jsonable({"a": np.array([1.0, np.nan]), "b": np.int64(3), "c": (np.bool_(True),)}) == {
        "a": [1.0, None], "b": 3, "c": [True]}
