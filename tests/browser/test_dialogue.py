"""The operator page's dialogue (issue 29, [OP] II and Fig. 5's Command Dialogue Box) in a real headless Chromium
against a real `hrp2-console`: a behaviour run from the page is told in words from start to outcome with its
details behind a click; a motion stop latched during a run is asked as a question with what raised it (the value
and the time) and released from the dialogue, the run's failure naming its cause; another client's command shows
the display name it chose, and this page's display name setting is validated and used. Every test saves a
screenshot (HRP2_ARTIFACTS, else pytest's tmp dir), like test_operator_page.py."""

from __future__ import annotations

import os
import re

import playwright.sync_api as playwright_api
import pytest

from tests.browser import test_operator_page as op
from tests.browser.test_operator_page import (
    get_json,
    motion_released,
    post_json,
    released,
    run_command,
    shot,
    wait_until,
)

# the operator page's fixtures, by name: its console, its Chromium page and where the screenshots go
hrp2_console, page, page_urls, artifacts = op.hrp2_console, op.page, op.page_urls, op.artifacts
saves_a_screenshot = op.saves_a_screenshot

pytestmark = pytest.mark.browser

DOC_SCREENSHOT = op.ROOT / "docs" / "img" / "operator_dialogue.png"  # written with HRP2_SAVE_PLOTS=1
expect = playwright_api.expect


def line(page, who: str, text: str | re.Pattern):
    """The dialogue's line said by `who` (you, robot, a client's display name) that contains `text`."""
    return page.locator(f'#history li[data-who="{who}"]').filter(has_text=text)


def run_of(c, behavior: str, after: int) -> dict:
    return wait_until(lambda: next((r for r in c.state()["runs"] if r["behavior"] == behavior and r["id"] > after),
                                   None), 10.0, f"a {behavior} run")


def ended(c, run_id: int, timeout: float) -> dict:
    return wait_until(lambda: next((r for r in c.state()["runs"] if r["id"] == run_id and r["state"] != "running"),
                                   None), timeout, f"run {run_id} to end")


def newest_run_id(c) -> int:
    return max((r["id"] for r in c.state()["runs"]), default=0)


def test_a_behaviour_run_from_the_page_is_told_in_words_from_start_to_outcome(page, hrp2_console, artifacts):
    released(hrp2_console)
    motion_released(hrp2_console)
    before = newest_run_id(hrp2_console)
    run_command(page, "squat 0.05")
    expect(line(page, "you", "squat 0.05")).to_have_count(1)  # the operator's own command, marked as theirs
    run = run_of(hrp2_console, "squat", before)
    expect(line(page, "robot", f"squat started (run {run['id']})")).to_have_count(1)
    done = ended(hrp2_console, run["id"], 40.0)
    assert done["state"] == "succeeded", done["message"]
    outcome = line(page, "robot", f"(run {run['id']})").filter(has_text="squat succeeded in")
    expect(outcome).to_have_count(1)
    words = outcome.locator(".words").inner_text()
    m = re.fullmatch(r"squat succeeded in ([\d.]+) s: (.*) \(run \d+\)", words)
    assert m and m.group(2) == done["message"], words  # the behaviour's own words for what it did
    assert float(m.group(1)) == pytest.approx(done["ended_s"] - done["started_s"], abs=0.051)  # (shown to 0.1 s)
    raw = outcome.locator("pre.raw")
    expect(raw).to_be_hidden()  # the details behind a click
    outcome.locator("summary").click()
    expect(raw).to_be_visible()
    expect(raw).to_contain_text(f'"id": {run["id"]}')
    expect(raw).to_contain_text('"state": "succeeded"')
    shot(page, artifacts, "dialogue_run_outcome")
    outcome.locator("summary").click()


def test_a_motion_stop_latched_during_a_run_is_asked_with_its_cause_and_released_from_the_dialogue(
        page, hrp2_console, artifacts):
    c = hrp2_console
    released(c)
    motion_released(c)
    wait_until(lambda: c.state()["layers"]["st"]["weight"] == 1.0, 10.0, "the Stabilizer fully on")
    before = newest_run_id(c)
    run_command(page, "look_at 1 1 1.2 rate_deg_s=2")  # the head turns slowly (~20 s): the push comes during it
    run = run_of(c, "look_at", before)
    wait_until(lambda: c.state()["time"] > run["started_s"] + 1.0, 10.0, "the run under way")
    # the push the page's latched-alert test uses: the CP flag rises, the EmergencyStopper latches the motion
    post_json(f"{c.base}/api/sim/push", {"body": "BODY", "force": [200.0, 0.0, 0.0], "duration": 0.1})
    em = wait_until(lambda: (e := c.state()["emergency"])["motion_stop"] and e, 5.0, "a motion stop from the CP flag")
    assert em["motion_stop_reason"] == "capture_point"
    # the question: what raised it, the value that raised it and when, and the button that releases it
    question = line(page, "robot", "motion stop latched by the capture-point flag")
    expect(question).to_have_count(1)
    words = question.locator(".words").inner_text()
    m = re.search(r"\(\|CP error\| ([\d.]+) mm when it rose, threshold ([\d.]+) mm\) at ([\d.]+) s", words)
    assert m, words
    assert float(m.group(1)) == pytest.approx(1000 * em["motion_stop_cp_error_m"], abs=0.051)  # what raised it
    assert float(m.group(2)) == pytest.approx(1000 * c.state()["capture_point"]["cp_threshold_m"], abs=0.051)
    assert float(m.group(3)) == pytest.approx(em["motion_stop_time"], abs=0.0006)  # and when
    # the run it ended: failed, its cause from the closed set, and the same one action
    failed = ended(c, run["id"], 5.0)
    assert failed["state"] == "failed" and failed["cause"] == "stop", failed
    outcome = line(page, "robot", re.compile(rf"look_at failed in [\d.]+ s: .*\(run {run['id']}\); "
                                             "cause: a latched stop"))
    expect(outcome).to_have_count(1)
    expect(outcome.get_by_role("button", name="Release the motion stop")).to_be_visible()
    # a behaviour asked for meanwhile is refused naming the stop, with the same one action
    run_command(page, "squat 0.05")
    refused = line(page, "robot", "refused (motion_stop): squat refused: the motion stop (EmergencyStopper) is latched")
    expect(refused).to_have_count(1)
    expect(refused.get_by_role("button", name="Release the motion stop")).to_be_visible()
    shot(page, artifacts, "dialogue_latched_stop")
    # released from the dialogue once the flag is down (a release while it is up would latch again)
    wait_until(lambda: not c.state()["emergency"]["flag"], 20.0, "the CP flag down")
    question.get_by_role("button", name="Release the motion stop").click()
    # (a click can wait ~20 s behind a software-GL frame of the 3D view on a loaded 2-CPU machine: the fixture's note)
    wait_until(lambda: not c.state()["emergency"]["motion_stop"], 30.0, "the motion stop released")
    expect(question).to_contain_text("- released")
    expect(question.get_by_role("button")).to_have_count(0)  # settled: no button left
    expect(outcome.get_by_role("button")).to_have_count(0)  # nor on the failure the stop caused
    expect(refused.get_by_role("button")).to_have_count(0)  # nor on the refusal
    expect(page.locator("#s-motion")).to_have_text("off")
    shot(page, artifacts, "dialogue_released")
    motion_released(c)
    assert not c.state()["fallen"]


def test_another_clients_command_shows_its_display_name_and_this_page_chooses_its_own(page, hrp2_console, artifacts):
    c = hrp2_console
    released(c)
    motion_released(c)
    answer = post_json(f"{c.base}/api/behaviors/look_at", {"x_m": 1.0, "y_m": 0.0, "z_m": 1.0}, client="Ann.script")
    said = line(page, "Ann.script", answer["message"])  # "look_at started (run N)", by the name Ann chose
    expect(said).to_have_count(1)
    said.locator("summary").click()
    expect(said.locator("pre.raw")).to_contain_text('"request": "POST /api/behaviors/look_at"')
    expect(line(page, "robot", re.compile(rf"look_at \w+ in [\d.]+ s: .*\(run {answer['id']}, another client's\)"))
           ).to_have_count(1, timeout=30_000)
    # this page's display name: a bad one is refused naming the field and what is allowed, a good one is used
    name = page.get_by_label("display name")
    name.fill("Bob Smith")
    page.get_by_role("button", name="Set name").click()
    expect(page.locator("#name-error")).to_have_text("display name: ' ' is not allowed; only A-Z a-z 0-9 . _ : -")
    name.fill("x" * 65)
    page.get_by_role("button", name="Set name").click()
    expect(page.locator("#name-error")).to_have_text("display name: 65 characters; 1 to 64 allowed")
    name.fill("Bob.console")
    page.get_by_role("button", name="Set name").click()
    expect(page.locator("#name-error")).to_be_empty()
    expect(page.locator("#history li").filter(has_text='you are now "Bob.console"')).to_have_count(1)
    page.get_by_role("button", name="Take control").click()
    wait_until(lambda: get_json(f"{c.base}/api/operator/lock")["holder"] == "Bob.console", 30.0,
               "the lock held as Bob.console")
    expect(page.locator("#lock-state")).to_have_text("control: YOU")
    # (a state naming the new holder may come before the lock's answer: it is this page, not another)
    expect(page.locator("#history li").filter(has_text="Bob.console took control")).to_have_count(0)
    assert c.state()["commands"][-1]["client"] == "Bob.console"  # the lock's request, by the chosen name
    shot(page, artifacts, "dialogue_display_name")
    if os.environ.get("HRP2_SAVE_PLOTS") == "1":  # the whole dialogue of this module's three tests, for the docs
        history = page.locator("#history")
        page.set_viewport_size({"width": 1280, "height": 1600})  # room for all of it in the controls' column
        history.evaluate("(h) => { h.style.maxHeight = 'none'; h.scrollIntoView({block: 'start'}); }")
        history.screenshot(path=str(DOC_SCREENSHOT))
        history.evaluate("(h) => { h.style.maxHeight = ''; }")
        page.set_viewport_size({"width": 1280, "height": 800})
    page.get_by_role("button", name="Release control").click()
    wait_until(lambda: get_json(f"{c.base}/api/operator/lock")["holder"] is None, 30.0, "the lock free")
