"""How well a paced loop keeps its deadlines: tick start-lateness and simulated time per wall second."""

from __future__ import annotations

from array import array
from collections import deque
from dataclasses import dataclass

import numpy as np

LATENESS_WINDOW = 12000  # ticks kept (60 s at 5 ms)
SPEED_WINDOWS = 120  # 1-s windows kept


@dataclass(frozen=True, slots=True)
class LoopTiming:
    """Tick start-lateness [ms] over the last ticks (how long after its scheduled wall time a tick began)
    and the simulated / wall time of the last whole 1-s wall windows."""

    ticks: int  # lateness samples the percentiles are taken over
    lateness_p50_ms: float
    lateness_p99_ms: float
    lateness_max_ms: float
    late_ticks_over_1ms: int
    speed_last: float | None  # simulated / wall time of the last finished 1-s window (None before the first)
    speed_min: float | None  # the slowest of the kept windows
    speed_run: float | None  # simulated / wall time since the run began (its start, last reset or speed change)
    windows: int
    paced: bool  # False when running as fast as it can (no schedule: lateness is 0)
    speed_target: float | None  # the real-time factor asked for (None = as fast as possible)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__slots__}


class LatenessMeter:
    """Fed once per tick by the paced loop; cheap to add to (a C array), summarised on demand."""

    def __init__(self, size: int = LATENESS_WINDOW) -> None:
        self._buf = array("d", bytes(8 * size))
        self._size = size
        self._n = 0
        self._windows: deque[float] = deque(maxlen=SPEED_WINDOWS)
        self._window_wall0: float | None = None
        self._window_sim0 = 0.0
        self._run_wall0: float | None = None  # [s] wall and simulated time at the run's first tick, and its last
        self._run_sim0 = self._last_wall = self._last_sim = 0.0
        self.speed_target: float | None = None

    def clear(self) -> None:
        self._n = 0
        self._windows.clear()
        self._window_wall0 = None
        self._run_wall0 = None

    def add(self, lateness_s: float, wall_s: float, sim_s: float) -> None:
        self._buf[self._n % self._size] = lateness_s * 1e3
        self._n += 1
        self._last_wall, self._last_sim = wall_s, sim_s
        if self._run_wall0 is None:
            self._run_wall0, self._run_sim0 = wall_s, sim_s
        if self._window_wall0 is None:
            self._window_wall0, self._window_sim0 = wall_s, sim_s
        elif wall_s - self._window_wall0 >= 1.0:
            self._windows.append((sim_s - self._window_sim0) / (wall_s - self._window_wall0))
            self._window_wall0, self._window_sim0 = wall_s, sim_s

    def summary(self, last_ticks: int | None = None, last_windows: int | None = None) -> LoopTiming:
        """The figures over the kept ticks, or the `last_ticks` of them (and the `last_windows` 1-s windows)."""
        n = min(self._n, self._size)
        s = np.frombuffer(self._buf, dtype=float, count=n)
        if last_ticks is not None and last_ticks < n:
            end = self._n % self._size if self._n > self._size else n
            idx = (np.arange(end - last_ticks, end)) % max(n, 1)
            s = s[idx]
            n = len(s)
        w = list(self._windows)
        if last_windows is not None:
            w = w[-last_windows:] if last_windows > 0 else []
        if n:
            p50, p99 = (float(v) for v in np.percentile(s, (50, 99)))
            mx, over = float(s.max()), int(np.count_nonzero(s > 1.0))
        else:
            p50 = p99 = mx = 0.0
            over = 0
        speed_run = None
        if self._run_wall0 is not None and self._last_wall > self._run_wall0:
            speed_run = round((self._last_sim - self._run_sim0) / (self._last_wall - self._run_wall0), 4)
        return LoopTiming(ticks=n, lateness_p50_ms=round(p50, 4), lateness_p99_ms=round(p99, 4),
                          lateness_max_ms=round(mx, 4), late_ticks_over_1ms=over,
                          speed_last=round(w[-1], 4) if w else None, speed_min=round(min(w), 4) if w else None,
                          speed_run=speed_run,
                          windows=len(w), paced=self.speed_target is not None, speed_target=self.speed_target)
