"""The targets kept for a release after an emergency stop: trimmed to the history, picked by the revert (unit)."""

import numpy as np

from controller.operation.release import ReleaseHistory


def kept(times, history_s=3.0):
    h = ReleaseHistory()
    h.started(times[0])
    for t in times:
        h.keep(t, {"rhand": t}, np.array([t]), history_s)
    return h


def test_a_release_restarts_from_the_last_entry_at_or_before_the_revert_and_uses_the_revert_up():
    h = kept([1.0, 1.5, 2.0, 2.5])
    h.revert_to_s = 2.2
    time_s, targets, q = h.release()
    assert (time_s, targets, q.tolist()) == (2.0, {"rhand": 2.0}, [2.0])
    assert h.revert_to_s is None and h.release() is None  # no revert any more


def test_a_revert_to_before_the_operation_or_no_revert_restarts_from_the_reference():
    h = kept([1.0, 1.5])
    assert h.release() is None
    h.revert_to_s = 0.5  # before the points became operated (1.0)
    assert h.release() is None


def test_entries_older_than_the_history_are_dropped_the_oldest_kept():
    h = kept([0.0, 1.0, 2.0, 3.0, 4.0], history_s=1.5)
    h.revert_to_s = 0.0
    assert h.release()[0] == 3.0  # 0-2 dropped: the oldest left is the one a too-early revert gets


def test_the_entries_are_copies_and_forget_clears_the_start():
    h = ReleaseHistory()
    targets, q = {"head": 1}, np.zeros(2)
    h.started(0.0)
    h.started(1.0)  # the first start counts
    h.keep(1.0, targets, q, 3.0)
    targets["head"], q[0] = 2, 5.0
    h.revert_to_s = 1.0
    _, kept_targets, kept_q = h.release()
    assert kept_targets == {"head": 1} and kept_q[0] == 0.0
    assert h.active_since_s == 0.0
    h.forget()
    h.revert_to_s = 1.0
    assert h.active_since_s is None and h.release() is None
    h.started(2.0)
    h.keep(2.0, {}, q, 3.0)
    h.drop_entries()
    h.revert_to_s = 2.0
    assert h.release() is None and h.active_since_s == 2.0
