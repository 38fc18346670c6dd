"""`make test` runs the suite in two passes (HRP2_TEST_PASS): first the in-process tests (the controller, the
robot model, the behaviours, the simulated scenarios) on two workers, then the rest one at a time: the tests that
drive a console, a browser or a worker pool of their own, or time the robot's loop, must not share the machine with
another test. Without HRP2_TEST_PASS, as a plain `pytest` runs, every test is selected."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
#: the folders whose tests run on the parallel pass, with the tests marked `in_process` elsewhere (tests/app's
#: TestClient ones); those marked `pool` excepted
PARALLEL_FOLDERS = ("controller", "robot", "behaviors", "scenarios")
PASSES = ("parallel", "serial")


def on_parallel_pass(item: pytest.Item) -> bool:
    folder = Path(str(item.path)).resolve().relative_to(TESTS).parts[0]
    in_process = folder in PARALLEL_FOLDERS or item.get_closest_marker("in_process") is not None
    return in_process and item.get_closest_marker("pool") is None


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    which = os.environ.get("HRP2_TEST_PASS")
    if not which:
        return
    if which not in PASSES:
        raise pytest.UsageError(f"HRP2_TEST_PASS={which!r}: allowed are {', '.join(PASSES)} (or unset: every test)")
    chosen = [on_parallel_pass(item) == (which == "parallel") for item in items]
    if not all(chosen):
        config.hook.pytest_deselected(items=[item for item, c in zip(items, chosen, strict=True) if not c])
        items[:] = [item for item, c in zip(items, chosen, strict=True) if c]
