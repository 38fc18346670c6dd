"""`make test` runs the suite in two passes (HRP2_TEST_PASS): first the in-process tests (the controller, the
robot model, the behaviours, the simulated scenarios) on two workers, then the rest one at a time: the tests that
drive a console, a browser or a worker pool of their own, or time the robot's loop, must not share the machine with
another test. Without HRP2_TEST_PASS, as a plain `pytest` runs, every test is selected."""

from __future__ import annotations

import os
from collections import Counter
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
#: the folders whose tests run on the parallel pass, with the tests marked `in_process` elsewhere (tests/app's
#: TestClient ones); those marked `pool` excepted
PARALLEL_FOLDERS = ("controller", "robot", "behaviors", "scenarios")
PASSES = ("parallel", "serial")
#: the parallel pass's longest files (minutes each), handed out first so that the pass does not end on one of them
#: with the other worker idle
LONGEST_FIRST = ("app/test_experiments_api.py", "scenarios/test_expo_behaviors.py", "scenarios/test_expo_carry.py",
                 "scenarios/test_expo_floor_object.py", "scenarios/test_walking_cp_flag.py")


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
    # items sharing a node id (schemathesis's, one per API operation) are told apart by none of xdist's schedulers,
    # which ran one of 48 of them: they run on the serial pass
    shared = {nodeid for nodeid, n in Counter(item.nodeid for item in items).items() if n > 1}
    chosen = [(on_parallel_pass(item) and item.nodeid not in shared) == (which == "parallel") for item in items]
    if not all(chosen):
        config.hook.pytest_deselected(items=[item for item, c in zip(items, chosen, strict=True) if not c])
        items[:] = [item for item, c in zip(items, chosen, strict=True) if c]
    if which == "parallel":
        first = {(TESTS / name).resolve() for name in LONGEST_FIRST}
        items.sort(key=lambda item: Path(str(item.path)).resolve() not in first)  # stable: the rest keep their order
