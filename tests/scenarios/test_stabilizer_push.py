"""Standing push recovery with the Stabilizer, and the capture-point flag when pushed past the threshold."""

import numpy as np
import pytest

from tests.scenarios.helpers import make_system, tilt_deg

PUSH_S = 0.1  # the impulse is delivered as a constant force over 0.1 s


def push_and_watch(impulse_ns: np.ndarray, stabilizer: bool = True, seconds: float = 4.0):
    """Stand 3 s, push BODY with `impulse_ns` [N s], watch; returns (fallen, worst tilt, snapshots)."""
    system = make_system()
    loop = system.loop
    if not stabilizer:
        loop.call(lambda: loop.chain["st"].stop())
    loop.run_for(3.0)
    loop.call(lambda: loop.plant.push("BODY", np.asarray(impulse_ns) / PUSH_S, PUSH_S))
    snaps = [loop.step() for _ in range(int(seconds / loop.dt_control_s))]
    worst = max(tilt_deg(s.truth.base_quat_wxyz) for s in snaps)
    return snaps[-1].fallen, worst, snaps


@pytest.mark.parametrize("impulse", [(20.0, 0.0, 0.0), (0.0, 30.0, 0.0), (-15.0, 0.0, 0.0)],
                         ids=["forward-20Ns", "left-30Ns", "backward-15Ns"])
def test_a_push_on_body_is_absorbed_with_the_stabilizer_on(impulse):
    fallen, worst, snaps = push_and_watch(np.array(impulse))
    assert not fallen
    assert worst < 10.0
    # and it comes back: after 4 s the capture-point error is small again
    assert snaps[-1].layers["st"].cp_error_norm < 0.02


def test_the_capture_point_error_is_in_every_snapshot_and_the_flag_rises_past_the_threshold():
    fallen, _, snaps = push_and_watch(np.array([20.0, 0.0, 0.0]), seconds=2.0)
    errors = np.array([s.layers["st"].cp_error_norm for s in snaps])
    flags = np.array([s.layers["st"].emergency for s in snaps])
    threshold = snaps[0].layers["st"].cp_threshold_m
    # 1. before the push the error is tiny and the flag down
    assert errors[0] < 0.01 and not flags[0]
    # 2. the push drives the error past the threshold and the flag follows it
    assert errors.max() > threshold
    assert flags.any()
    assert np.array_equal(flags, errors > threshold)
    assert snaps[-1].layers["st"].flag_rose_at is not None


@pytest.mark.slow
def test_the_stabilizer_absorbs_a_forward_push_that_topples_the_robot_without_it():
    impulse = np.array([26.0, 0.0, 0.0])
    fallen_with, _, _ = push_and_watch(impulse, stabilizer=True)
    fallen_without, _, _ = push_and_watch(impulse, stabilizer=False)
    assert not fallen_with
    assert fallen_without
