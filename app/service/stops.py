"""The latched stops no behaviour runs under (the EmergencyStopper's motion stop, the AutoBalancer's emergency
walking stop), each told as what it is, what raised it and when, and what releases it: the words of a refused
behaviour and of a run the stop ended."""

from __future__ import annotations

from dataclasses import dataclass

from behaviors.runner import LatchedStop

__all__ = ["LatchedStop", "WalkingStopWatch", "motion_stop"]


def _mm(value_m: float | None) -> str:
    return "?" if value_m is None else f"{1000.0 * value_m:.1f} mm"


def _at(time_s: float | None) -> str:
    return "at an unknown time" if time_s is None else f"at t = {time_s:.3f} s (simulated)"


def capture_point_words(cp_error_m: float | None) -> str:
    """'the capture-point flag (|CP error| 43.4 mm when it rose)': the value that raised it, not the value now."""
    return f"the capture-point flag (|CP error| {_mm(cp_error_m)} when it rose)"


_MOTION_RAISED_BY = {
    "operator": "the operator (POST /api/motion/stop)",
    "emergency_step": "the AutoBalancer's capture-point emergency step",
}


def motion_stop(es) -> LatchedStop | None:
    """The EmergencyStopper's stop (`es`, the layer, or None), if it holds the motion."""
    if es is None or not es.enabled or not es.stopped:
        return None
    if es.reason == "capture_point":
        by = capture_point_words(es.cp_error_m)
    else:
        by = _MOTION_RAISED_BY.get(es.reason, repr(es.reason))
    return LatchedStop(
        reason="motion_stop", raised_by=str(es.reason), time_s=es.flag_time_s,
        message=(f"the motion stop (EmergencyStopper) is latched, raised by {by} {_at(es.flag_time_s)}; "
                 "POST /api/motion/release releases it (balance keeps working meanwhile)"),
        points=None)


@dataclass
class _Rise:
    raised_by: str
    words: str
    time_s: float


class WalkingStopWatch:
    """What raised the AutoBalancer's emergency walking stop, and when: watched at every tick boundary (the
    AutoBalancer keeps no cause). Raised by the operator (`asked`, set by the walk_emergency_stop verb), by the
    hard e-stop (a walk it cut stops in place after its release) or else by the capture-point flag."""

    def __init__(self) -> None:
        self.asked = False  # the operator asked for it since the last boundary
        self._rise: _Rise | None = None

    def observe(self, time_s: float, abc, st, hard_stop: bool) -> None:
        in_force = abc is not None and abc.enabled and abc.walking_stop
        if not in_force:
            self._rise = None
        elif self._rise is None:
            if self.asked:
                self._rise = _Rise("operator", "the operator (POST /api/walk/emergency-stop)", time_s)
            elif hard_stop:
                self._rise = _Rise("hard_stop", "the hard e-stop (the walk it cut stops in place after its release)",
                                   time_s)
            else:
                rose = getattr(st, "flag_rose_at_s", None)
                self._rise = _Rise("capture_point", capture_point_words(getattr(st, "flag_cp_error_m", None)),
                                   time_s if rose is None else rose)
        self.asked = False

    def stop(self) -> LatchedStop | None:
        rise = self._rise
        if rise is None:
            return None
        return LatchedStop(
            reason="walking_stop", raised_by=rise.raised_by, time_s=rise.time_s,
            message=(f"the emergency walking stop (AutoBalancer) is in force, raised by {rise.words} "
                     f"{_at(rise.time_s)}; it ends by itself once the robot stands still (GET /api/state: "
                     "emergency.walking_stop false)"),
            points=("walk",))
