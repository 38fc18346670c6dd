"""Delta debugging (Zeller's ddmin): the shortest action list found that still violates the same invariant."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TypeVar

T = TypeVar("T")


def ddmin(items: Sequence[T], fails: Callable[[list[T]], bool], max_tests: int = 64) -> list[T]:
    """A 1-minimal sublist of `items` (order kept) for which `fails` holds, given that it holds for `items`;
    at most `max_tests` calls of `fails` (then the smallest failing list found so far)."""
    current = list(items)
    n, tests = 2, 0
    while len(current) >= 2 and tests < max_tests:
        size = len(current) / n
        chunks = [current[round(i * size):round((i + 1) * size)] for i in range(n)]
        reduced = False
        for i, chunk in enumerate(chunks):  # a chunk alone, then everything but a chunk
            for candidate in (chunk, [x for j, c in enumerate(chunks) if j != i for x in c]):
                if not candidate or len(candidate) == len(current) or tests >= max_tests:
                    continue
                tests += 1
                if fails(candidate):
                    current, n, reduced = candidate, (2 if candidate is chunk else max(n - 1, 2)), True
                    break
            if reduced:
                break
        if not reduced:
            if n >= len(current):
                break
            n = min(n * 2, len(current))
    if len(current) == 1 and tests < max_tests and fails([]):
        return []
    return current
