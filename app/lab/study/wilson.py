"""Wilson score interval of a success share: the confidence the study gives its rates with."""

from __future__ import annotations

import math

Z_95 = 1.959963984540054  # two-sided 95 %


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float] | None:
    """(low, high) of the share successes / n at the confidence `z` gives (95 % by default); None when n = 0."""
    if not 0 <= successes <= n:
        raise ValueError(f"successes must be in 0..n, got {successes} of {n}")
    if n == 0:
        return None
    p = successes / n
    denominator = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denominator
    low = 0.0 if successes == 0 else max(0.0, centre - half)  # exact at the edges (no 0.9999999999999999)
    high = 1.0 if successes == n else min(1.0, centre + half)
    return low, high
