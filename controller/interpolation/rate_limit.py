"""A value moved toward a target by at most a bounded step per tick (a rate limit, both ways)."""

from __future__ import annotations


def approach(value: float, target: float, max_step: float) -> float:
    """`value` moved toward `target` by at most `max_step` (>= 0, the rate times the tick), landing on it exactly."""
    return min(value + max_step, target) if target > value else max(value - max_step, target)
