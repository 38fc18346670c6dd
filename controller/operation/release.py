"""The targets kept over the last seconds, so that a release after an emergency stop restarts the points from
the ones the stop's revert went back to."""

from __future__ import annotations

from collections import deque

import numpy as np


class ReleaseHistory:
    """(control time [s], targets, the IK's configuration) per operated tick over the last `history_s`;
    `revert_to_s` is the time the EmergencyStopper reverted to (None: no revert under way), `active_since_s`
    when the points became operated (None: not operated)."""

    __slots__ = ("_entries", "revert_to_s", "active_since_s")

    def __init__(self) -> None:
        self._entries: deque[tuple[float, dict, np.ndarray]] = deque()
        self.revert_to_s: float | None = None
        self.active_since_s: float | None = None

    def started(self, time_s: float) -> None:
        """An operated tick at `time_s` [s]: the first one since `forget` marks the start."""
        if self.active_since_s is None:
            self.active_since_s = time_s

    def keep(self, time_s: float, targets: dict, q: np.ndarray, history_s: float) -> None:
        """This tick's targets (copied) and configuration `q` (copied); entries older than `history_s` [s] before
        it dropped, the oldest one kept."""
        h = self._entries
        h.append((time_s, dict(targets), q.copy()))
        while len(h) > 1 and h[0][0] < time_s - history_s:
            h.popleft()

    def drop_entries(self) -> None:
        """The kept targets no longer apply (re-expressed in another anchor): a release restarts from the present."""
        self._entries.clear()

    def forget(self) -> None:
        """Nothing operated any more."""
        self._entries.clear()
        self.active_since_s = None

    def release(self) -> tuple[float, dict, np.ndarray] | None:
        """The entry a release restarts from: the last one at or before the revert's time (the revert is used
        up); None when the revert went back to before anything was operated (restart from the reference)."""
        t_rev, self.revert_to_s = self.revert_to_s, None
        return self.entry_at(t_rev)

    def entry_at(self, t_rev: float | None) -> tuple[float, dict, np.ndarray] | None:
        """The last entry at or before `t_rev` [s]; None when that is before anything was operated (or None)."""
        if t_rev is None or self.active_since_s is None or t_rev < self.active_since_s or not self._entries:
            return None
        entry = self._entries[0]
        for e in self._entries:
            if e[0] <= t_rev + 1e-9:
                entry = e
            else:
                break
        return entry
