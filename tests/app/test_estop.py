"""The e-stop's one semantics (app.service.estop): what an e-stop message is, what a press id is, which press is a
late copy; and the host that applies them to the loop."""

import json
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.service.errors import Refused
from app.service.estop import COPY_WINDOW_S, EstopAck, PressLog, parse_message, parse_text, request_of
from app.service.verbs import ReleaseEstop


def ack_at(t_s: float) -> EstopAck:
    return EstopAck(tick=1, sim_time_s=0.0, engaged_at_monotonic_s=t_s, engaged=True)


@pytest.mark.parametrize("text", ['{"estop": true}', '{ "estop" : true }', '{"press": "k1", "estop": true}',
                                  '{\n "estop": true\n}', '{"\\u0065stop": true}', '{"estop": true, "more": [1]}'])
def test_every_json_spelling_of_an_object_whose_estop_is_true_is_an_estop(text):
    assert parse_text(text) is not None


@pytest.mark.parametrize("text", ['{"estop": false}', '{"estop": 1}', '{"estop": "true"}', "[]", "null", "estop",
                                  '"estop"', b"\xff\xfe", "[" * 100_000, "", '{"estop": true'])
def test_anything_else_is_not_an_estop_and_never_raises(text):
    assert parse_text(text) is None


@given(st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(),
                    lambda inner: st.lists(inner) | st.dictionaries(st.text(), inner), max_leaves=20))
@settings(max_examples=500, deadline=None)
def test_any_json_value_is_an_estop_exactly_when_it_is_an_object_whose_estop_is_true(value):
    expected = isinstance(value, dict) and value.get("estop") is True
    assert (parse_message(value) is not None) is expected
    assert (parse_text(json.dumps(value)) is not None) is expected


@pytest.mark.parametrize("press", ["", "x" * 65, "a b", 7, ["p"], "p;q"])
def test_a_malformed_press_id_is_set_aside_with_the_rule_and_the_stop_still_asked_for(press):
    request = parse_message({"estop": True, "press": press})
    assert request is not None and request.press is None and "1 to 64 characters" in request.press_ignored
    assert request_of("page-1:7").press == "page-1:7"


def test_a_copy_of_a_press_released_since_is_late_within_the_window_and_a_new_press_after_it():
    log = PressLog()
    first = ack_at(10.0)
    log.pressed("p", first)
    assert log.first("p", 10.1) is first and not log.released_after(first)
    log.released(10.2)
    assert log.first("p", 10.3) is first and log.released_after(first)  # a late copy
    assert log.first("p", 10.0 + COPY_WINDOW_S) is None  # the same id later: a new press
    assert log.first("q", 10.3) is None


def test_only_a_press_s_first_copy_is_kept_and_old_presses_are_forgotten():
    log = PressLog()
    first = ack_at(1.0)
    log.pressed("p", first)
    log.pressed("p", ack_at(1.01))
    assert log.first("p", 1.02) is first
    log.pressed("q", ack_at(5.0))
    assert log._first.keys() == {"q"}


def test_the_answer_is_ok_exactly_when_engaged_and_a_late_copy_says_why():
    assert ack_at(0.0).reply()["ok"] is True
    late = EstopAck(tick=1, sim_time_s=0.0, engaged_at_monotonic_s=0.0, engaged=False, late_copy=True)
    body = late.reply(via="door")
    assert body["ok"] is False and body["reason"] == "late_copy" and body["via"] == "door"
    assert "not engaged" in body["message"]


def test_the_host_engages_every_press_but_a_late_copy_and_answers_a_copy_with_its_first_answer(runtime):
    host = runtime.host
    runtime.run_for(0.05)
    first = host.engage_estop("page-1:1")
    assert first.engaged and not first.already_engaged and host.loop.hard_stop_engaged
    copy = host.engage_estop("page-1:1")  # the same press by another way, the stop still engaged
    assert copy.copy and copy.engaged and copy.engaged_at_monotonic_s == first.engaged_at_monotonic_s
    assert host.engage_estop("other").already_engaged
    host.release_estop()
    late = host.engage_estop("page-1:1")
    assert late.late_copy and not late.engaged and not host.loop.hard_stop_engaged
    again = host.engage_estop("page-1:2")
    assert again.engaged and host.loop.hard_stop_engaged
    host.release_estop()
    assert host.engage_estop(None).engaged  # no id: always a new press


def test_a_press_handled_after_a_release_was_sent_is_not_released_by_it_and_a_copy_does_not_count():
    log = PressLog()
    log.pressed("a", EstopAck(tick=1, sim_time_s=0.0, engaged_at_monotonic_s=10.0, engaged=True))
    assert not log.pressed_since(10.0) and log.pressed_since(9.99)
    log.pressed("b", EstopAck(tick=2, sim_time_s=0.0, engaged_at_monotonic_s=10.5, engaged=True,
                              already_engaged=True))  # another client's press, the stop already engaged
    assert log.pressed_since(10.2) and not log.pressed_since(10.5)


def test_a_release_sent_before_another_clients_press_leaves_the_stop_engaged(runtime):
    # the robot process reads the e-stop pipe and the door before the commands: a release sent before another
    # client's press can be handled after that press, which then answered "already engaged"
    host = runtime.host
    runtime.run_for(0.05)
    assert host.engage_estop("page-1:1").engaged
    sent_s = time.monotonic()
    assert host.engage_estop("page-1:1").copy  # a copy of the press the release is for: does not count
    host.release_estop(sent_monotonic_s=sent_s)
    assert not host.loop.hard_stop_engaged
    assert host.engage_estop("page-1:2").engaged
    sent_s = time.monotonic()
    assert host.engage_estop("page-2:1").already_engaged  # another client presses after the release was sent
    with pytest.raises(Refused) as refused:
        runtime.submit(ReleaseEstop(0, sent_s)).result()
    assert refused.value.reason == "hard_stop" and "pressed after this release was sent" in str(refused.value)
    assert host.loop.hard_stop_engaged
    runtime.submit(ReleaseEstop(0, time.monotonic())).result()  # released again, after the press
    assert not host.loop.hard_stop_engaged
