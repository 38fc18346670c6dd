"""The progress bar: runs done, share of the simulated time, elapsed time and the estimate of what is left."""

import io

import pytest

from app.lab.study.progress import Progress, clock_text

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_the_estimate_is_the_wall_time_per_simulated_second_times_what_is_left():
    clock, out = Clock(), io.StringIO()
    p = Progress("tuning", 4, 40.0, stream=out, clock=clock, interval_s=0.0)
    p.start()
    assert p.eta_s() is None and "0/4 runs" in out.getvalue() and "ETA --" in out.getvalue()
    clock.t += 30.0
    p.done(10.0)  # a quarter of the simulated time in 30 s: 90 s left
    assert p.eta_s() == 90.0
    assert out.getvalue().splitlines()[-1] == ("tuning [######..................] 1/4 runs  25 %  elapsed 0:30  "
                                               "ETA 1:30")


def test_off_a_terminal_it_prints_a_line_at_most_every_interval_and_at_the_end():
    clock, out = Clock(), io.StringIO()
    p = Progress("validation", 3, 3.0, stream=out, clock=clock, interval_s=10.0)
    p.start()
    for _ in range(3):
        clock.t += 1.0
        p.done(1.0)
    lines = out.getvalue().splitlines()
    assert len(lines) == 2 and "3/3 runs 100 %" in lines[-1] and "\r" not in out.getvalue()


def test_clock_text_shows_hours_only_when_there_are_some():
    assert clock_text(59.6) == "1:00" and clock_text(3725) == "1:02:05" and clock_text(-3) == "0:00"
