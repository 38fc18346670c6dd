"""Browser test hooks: each test's call outcome kept on its item (`rep_call`), for fixtures that check what a
passed test left behind (its screenshot)."""

import pytest


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.when == "call":
        item.rep_call = report
