"""Delta debugging reduces a failing list to a 1-minimal one, keeping order, within its test budget."""

from __future__ import annotations

import pytest

from app.lab.campaign.shrink import ddmin

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_two_culprits_among_forty_items_are_all_that_is_left():
    calls = []

    def fails(items):
        calls.append(len(items))
        return 7 in items and 31 in items

    assert ddmin(list(range(40)), fails) == [7, 31]


def test_an_order_dependent_failure_keeps_the_order():
    def fails(items):
        return "estop" in items and "push" in items and items.index("estop") < items.index("push")

    assert ddmin(["walk", "estop", "stick", "push", "reset"], fails) == ["estop", "push"]


def test_a_failure_of_one_item_shrinks_to_that_item():
    assert ddmin(list(range(17)), lambda items: 16 in items) == [16]


def test_the_budget_bounds_the_calls_and_the_answer_still_fails():
    calls = []

    def fails(items):
        calls.append(1)
        return sum(items) >= 50

    got = ddmin(list(range(30)), fails, max_tests=5)
    assert len(calls) <= 5 and sum(got) >= 50
