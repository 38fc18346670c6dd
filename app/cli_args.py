"""Argument types of the command lines (the console's and the campaign's): each error names what would have been
accepted."""

from __future__ import annotations

import argparse
import math


def speed_or_max(text: str) -> float | None:
    if text.strip().lower() == "max":
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(
            f"invalid value {text!r}: expected a positive real-time factor (e.g. 1.0, 0.5, 4) or 'max'")
    return value


def positive(expected: str):
    """An argparse type: a finite number > 0, or an error saying `expected`."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected {expected}")
        return value

    return parse


positive_seconds = positive("a number of seconds > 0")
positive_float = positive("a number > 0")


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected a whole number >= 1")
    return value
