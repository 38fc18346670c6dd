"""One e-stop semantics for every way in (app.service.estop), checked from outside on a real console paced at real
time (POST /api/estop, the stick stream, the robot's own door) and on the 3D view's button: a press with a fresh
id, with an id reused after a release, and in any JSON spelling engages; a late copy of a press already released
does not; and no way answers ok while the loop does not have the stop engaged (asserted on the loop's state)."""

from __future__ import annotations

import json
import time

import pytest
from websockets.sync.client import connect

from app.lab.console_process import Console
from app.service.estop import COPY_WINDOW_S

pytestmark = pytest.mark.slow
SPELLINGS = ['{"estop": true, "press": "%s"}', '{ "estop" : true , "press" : "%s" }', '{"press": "%s", "estop": true}',
             '{\n  "press": "%s",\n  "estop": true\n}', '{"\\u0065stop": true, "press": "%s"}',
             '{"estop": true, "press": "%s", "note": "from a bridge"}']


@pytest.fixture(scope="module")
def console():
    with Console("--speed", "1.0") as c:
        _, cfg = c.request("GET", "/api/config")
        c.door_port = cfg["estop_port"]
        yield c


class Way:
    """Sends a press one way and returns (answered ok, the whole answer)."""

    def __init__(self, console: Console, name: str) -> None:
        self.console, self.name = console, name
        self.page = f"http://127.0.0.1:{console.port}"

    def press(self, press: str, spelling: str = SPELLINGS[0]) -> tuple[bool, dict]:
        if self.name == "http":
            status, body = self.console.request("POST", "/api/estop", headers={"X-Estop-Press": press})
            assert (status == 200) is bool(body.get("ok")), (status, body)
            return bool(body["ok"]), body
        url = (f"ws://127.0.0.1:{self.console.door_port}/" if self.name == "door"
               else f"ws://127.0.0.1:{self.console.port}/ws/operator")
        with connect(url, origin=self.page, open_timeout=5.0) as ws:
            ws.send(spelling % press)
            body = json.loads(ws.recv(timeout=5.0))
        assert body.get("estop") is True, body
        return bool(body.get("ok")), body


def engaged(console: Console, tick: int = -1) -> bool:
    return console.hard_stop_after(tick)


def released(console: Console) -> None:
    status, body = console.request("POST", "/api/estop/release")
    assert status == 200, body
    deadline = time.monotonic() + 2.0
    while engaged(console):
        assert time.monotonic() < deadline
        time.sleep(0.02)


def after_the_window() -> None:
    time.sleep(COPY_WINDOW_S + 0.05)


@pytest.mark.parametrize("way", ["http", "stream", "door"])
def test_a_fresh_press_and_a_press_id_reused_after_a_release_both_engage(console, way):
    w = Way(console, way)
    for round_ in range(3):  # the same id each time, as a button bridge with a fixed id sends it
        ok, body = w.press("big-red-button")
        assert ok and engaged(console, body["tick"]), (round_, body)
        released(console)
        after_the_window()


@pytest.mark.parametrize("way", ["stream", "door"])
@pytest.mark.parametrize("spelling", SPELLINGS, ids=range(len(SPELLINGS)))
def test_any_json_spelling_of_an_estop_engages(console, way, spelling):
    ok, body = Way(console, way).press(f"spelling-{way}-{SPELLINGS.index(spelling)}", spelling)
    assert ok and engaged(console, body["tick"]), body
    released(console)


@pytest.mark.parametrize("first, copy", [("http", "stream"), ("door", "http"), ("stream", "door")])
def test_a_late_copy_of_a_released_press_within_the_window_engages_nothing_and_is_not_answered_ok(console, first,
                                                                                                 copy):
    press = f"page-{first}-{copy}:{time.monotonic_ns()}"
    ok, body = Way(console, first).press(press)
    assert ok and engaged(console, body["tick"])
    released(console)
    ok, body = Way(console, copy).press(press)  # well within COPY_WINDOW_S of the first copy
    assert not ok and body["late_copy"] is True and body["reason"] == "late_copy", body
    assert not engaged(console, body["tick"] + 20)  # nor 0.1 s later
    after_the_window()
    ok, body = Way(console, copy).press(press)  # the same id, later: a new press
    assert ok and engaged(console, body["tick"])
    released(console)


def test_no_answer_says_ok_unless_the_loop_has_the_stop_engaged(console):
    """Every way, with fresh, reused, late and malformed ids, each answer checked against the loop's own state."""
    ways = [Way(console, w) for w in ("http", "stream", "door")]
    seen = []
    for i in range(12):
        way = ways[i % 3]
        press = [f"p-{i}", "p-reused", "bad id!", f"p-{i - 1}"][i % 4]
        ok, body = way.press(press)
        seen.append((way.name, press, ok))
        assert ok is engaged(console, body["tick"]), (way.name, press, body)
        if i % 2:
            released(console)
    assert any(ok for *_, ok in seen)


def test_the_3d_views_button_engages_and_shows_the_loops_answer():
    from app.console.viewer import Viewer
    from app.service import OperatorService
    from app.service.local import LocalRobot

    robot = LocalRobot(speed=None)
    viewer = Viewer(OperatorService(robot), host="127.0.0.1", port=0, rate_hz=50.0)
    try:
        robot.run_for(0.05)
        for _ in range(3):  # every click a new press: after a release, the next click engages again
            viewer.press_estop()
            assert robot.host.loop.hard_stop_engaged
            assert viewer._message.value == "hard e-stop engaged"
            viewer.service.release_estop()
            robot.run_for(0.05)
            assert not robot.host.loop.hard_stop_engaged
    finally:
        viewer.stop()
        robot.stop()
