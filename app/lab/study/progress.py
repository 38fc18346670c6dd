"""A plain-text progress bar with the estimated time left, on stderr: redrawn in place on a terminal, a line
every `interval_s` otherwise (logs, CI)."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

BAR_WIDTH = 24


def clock_text(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class Progress:
    """`total_runs` runs of `total_sim_s` simulated seconds in all; `done(sim_s)` after each. The estimate is
    the wall time per simulated second so far times the simulated seconds left (runs differ in length)."""

    def __init__(self, label: str, total_runs: int, total_sim_s: float, stream: TextIO | None = None,
                 clock: Callable[[], float] = time.monotonic, interval_s: float = 10.0) -> None:
        self.label = label
        self.total_runs = total_runs
        self.total_sim_s = total_sim_s
        self.stream = sys.stderr if stream is None else stream
        self.clock = clock
        self.interval_s = interval_s
        self.t0 = clock()
        self.runs = 0
        self.sim_s = 0.0  # expected simulated seconds of the runs done
        self._last_print = -float("inf")
        self._tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def eta_s(self) -> float | None:
        """[s] of wall time left, None before the first run is done."""
        if self.sim_s <= 0.0:
            return None
        return (self.clock() - self.t0) * max(0.0, self.total_sim_s - self.sim_s) / self.sim_s

    def line(self) -> str:
        share = self.sim_s / self.total_sim_s if self.total_sim_s > 0 else 1.0
        filled = int(round(BAR_WIDTH * min(1.0, share)))
        eta = self.eta_s()
        return (f"{self.label} [{'#' * filled}{'.' * (BAR_WIDTH - filled)}] {self.runs}/{self.total_runs} runs "
                f"{100 * share:3.0f} %  elapsed {clock_text(self.clock() - self.t0)}  "
                f"ETA {'--' if eta is None else clock_text(eta)}")

    def done(self, expected_sim_s: float) -> None:
        self.runs += 1
        self.sim_s += expected_sim_s
        now = self.clock()
        finished = self.runs >= self.total_runs
        if self._tty:
            self.stream.write("\r" + self.line() + ("\n" if finished else ""))
        elif finished or now - self._last_print >= self.interval_s:
            self.stream.write(self.line() + "\n")
            self._last_print = now
        self.stream.flush()

    def start(self) -> None:
        """The bar at zero (and, off a terminal, one line saying how much there is to do)."""
        self.stream.write(("\r" if self._tty else "") + self.line() + ("" if self._tty else "\n"))
        self.stream.flush()
        self._last_print = self.clock()
