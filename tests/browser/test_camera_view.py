"""A full EXPO run from the operator page (issue 29) in a real headless Chromium against a real `hrp2-console` in the
EXPO scene: each behaviour typed in the command box, each step told in the dialogue in words, the recognitions
confirmed from their pop-ups, which stay inside the camera frame with their text whole (1280x800, 1920x1080, the
frame resized); the can's pop-up goes once take_can holds it (no second Confirm beside another), and after
throw_can the page shows "in the box" where the robot saw the can end. The console runs without its 3D view
(--headless: the camera is the page's own stream), which spares software WebGL's load. Every test saves a
screenshot (HRP2_ARTIFACTS, else pytest's tmp dir), like test_operator_page.py."""

from __future__ import annotations

import re
from pathlib import Path

import playwright.sync_api as playwright_api
import pytest

from tests.browser import test_operator_page as op
from tests.browser.test_dialogue import line, newest_run_id, run_of
from tests.browser.test_operator_page import get_json, post_json, run_command, shot, wait_until

# the operator page's fixtures, by name (its page opens on this module's console): the Chromium page, where the
# screenshots go
page, page_urls, artifacts, saves_a_screenshot = op.page, op.page_urls, op.artifacts, op.saves_a_screenshot

pytestmark = pytest.mark.browser

SIZES = ((1280, 800), (1920, 1080))
#: [px] the camera frame resized to these (its corner): the smallest it allows and a larger one
FRAME_SIZES = ((240, 180), (480, 360))
#: [s] of simulated time at most per behaviour (take_can measured ~60 s, throw_can ~50 s with its look)
RUN_TIMEOUT_S = 150.0
_POPUPS = """() => { const f = document.getElementById('camera-frame').getBoundingClientRect();
  return [[f.left, f.top, f.right, f.bottom], [...document.querySelectorAll('.rec-pop')].map((p) => {
    const r = p.getBoundingClientRect();
    return [p.textContent, r.left, r.top, r.right, r.bottom, p.scrollWidth - p.clientWidth,
            p.scrollHeight - p.clientHeight]; })]; }"""


@pytest.fixture(scope="module")
def hrp2_console():
    if not Path(op.CHROMIUM).exists():
        pytest.skip(f"no Chromium at {op.CHROMIUM} (`make browser` installs Debian's)")
    c = op.start_console(["--port", "0", "--headless"])
    try:
        yield c
    finally:
        c.stop()


def run_from_the_page(page, c: op.Console, behavior: str) -> dict:
    """`behavior` typed in the command box and run to its end; the dialogue says the operator's command, the run's
    start and its outcome in words (`... succeeded in N s: <its message> (run N)`)."""
    before = newest_run_id(c)
    run_command(page, behavior)
    playwright_api.expect(line(page, "you", behavior)).to_have_count(1, timeout=10_000)
    run = run_of(c, behavior, before)
    playwright_api.expect(line(page, "robot", f"{behavior} started (run {run['id']})")).to_have_count(1)
    done = wait_until(lambda: next((r for r in c.state()["runs"] if r["id"] == run["id"] and r["state"] != "running"),
                                   None), RUN_TIMEOUT_S, f"{behavior} to end", period=0.5)
    assert done["state"] == "succeeded", done["message"]
    outcome = line(page, "robot", f"(run {run['id']})").filter(has_text=f"{behavior} succeeded in")
    playwright_api.expect(outcome).to_have_count(1)
    assert done["message"] in outcome.locator(".words").inner_text()  # the behaviour's own words
    return done


def stepped_from_the_preview(page, c: op.Console, behavior: str) -> dict:
    """`behavior` previewed from its form and run with Step: each phase runs, then the run holds (the robot not
    walking) until the next Step. Returns the ended run and the phases stepped."""
    before = newest_run_id(c)
    page.locator("#behaviors").get_by_role("button", name=behavior, exact=True).click()
    page.locator("#behavior-form").get_by_role("button", name="Preview").click()
    step = page.locator("#preview").get_by_role("button", name=re.compile(r"^Step"))
    step.click()
    run = run_of(c, behavior, before)
    phases = []
    while True:
        now = wait_until(lambda: next((r for r in c.state()["runs"] if r["id"] == run["id"]
                                       and (r["waiting"] or r["state"] != "running")), None),
                         RUN_TIMEOUT_S, f"{behavior}'s next phase", period=0.2)
        if now["state"] != "running":
            break
        phases.append(now["result"]["phase"])
        if len(phases) == 1:  # held: nothing moves on before the operator's Step
            page.wait_for_timeout(1000)
            held = c.state()
            assert held["layers"]["abc"]["walking"] is False
            assert next(r for r in held["runs"] if r["id"] == run["id"])["waiting"]
        playwright_api.expect(step).to_have_text(f"Step (next: {phases[-1]})")
        step.click()
        wait_until(lambda: not next(r for r in c.state()["runs"] if r["id"] == run["id"])["waiting"], 10.0,
                   f"{behavior} stepped on")
    assert now["state"] == "succeeded", now["message"]
    outcome = line(page, "robot", f"(run {run['id']})").filter(has_text=f"{behavior} succeeded in")
    playwright_api.expect(outcome).to_have_count(1)
    return now, phases


def confirm_from_the_popup(page, c: op.Console, name: str) -> None:
    """The recognition `name` confirmed with its pop-up's button; the robot has it confirmed, the dialogue says so."""
    pop = page.locator(".rec-pop", has_text=f"{name} at")
    pop.get_by_role("button", name="Confirm").click()
    wait_until(lambda: get_json(f"{c.base}/api/recognitions")["recognitions"][name].get("status") == "confirmed",
               10.0, f"the {name} confirmed")
    playwright_api.expect(pop).to_contain_text("confirmed")
    playwright_api.expect(page.locator("#history")).to_contain_text(f"{name} confirmed at (")


def popups_inside(page, where: str) -> list:
    """Every pop-up inside the camera frame with nothing of its text scrolled away; returns them."""
    frame, pops = page.evaluate(_POPUPS)
    assert pops, f"no pop-up ({where})"
    for text, left, top, right, bottom, hidden_w, hidden_h in pops:
        inside = left >= frame[0] - 0.5 and top >= frame[1] - 0.5 and right <= frame[2] + 0.5 and \
            bottom <= frame[3] + 0.5
        assert inside, f"the pop-up {text!r} at {(left, top, right, bottom)} leaves the frame {frame} ({where})"
        assert hidden_w <= 1 and hidden_h <= 1, f"the pop-up {text!r} is cut ({hidden_w}, {hidden_h} px; {where})"
    return pops


def test_expo_from_the_page_locate_can_its_popup_inside_the_frame_confirmed_from_it(page, hrp2_console, artifacts):
    post_json(f"{hrp2_console.base}/api/sim/reset", {"scene": "expo"}, timeout=60.0)
    wait_until(lambda: hrp2_console.state()["scene"] == "expo", 30.0, "the expo scene")
    run_from_the_page(page, hrp2_console, "locate_can")
    # the camera renders the new scene in a new process: on a loaded 2-core machine its first frame came >15 s late
    playwright_api.expect(page.locator(".rec-pop")).to_have_count(1, timeout=60_000)
    for w, h in SIZES:
        page.set_viewport_size({"width": w, "height": h})
        page.wait_for_timeout(1000)  # a few frames laid out at the new size
        popups_inside(page, f"{w}x{h}")
        shot(page, artifacts, f"camera_popups_{w}x{h}")
    for w, h in FRAME_SIZES:  # the frame's corner dragged: the same as setting its size
        page.evaluate(f"(() => {{ const f = document.getElementById('camera-frame'); f.style.width = '{w}px'; "
                      f"f.style.height = '{h}px'; }})()")
        page.wait_for_timeout(1000)
        assert page.locator("#camera-img").bounding_box()["width"] == pytest.approx(w, abs=1)  # the image follows
        popups_inside(page, f"frame {w}x{h}")
        shot(page, artifacts, f"camera_frame_{w}x{h}")
    page.evaluate("(() => { const f = document.getElementById('camera-frame'); f.style.width = ''; "
                  "f.style.height = ''; })()")
    page.set_viewport_size({"width": 1280, "height": 800})
    confirm_from_the_popup(page, hrp2_console, "can")


def test_expo_from_the_page_take_can_its_popup_goes_and_the_boxs_is_confirmed(page, hrp2_console, artifacts):
    """In the EXPO trial's order ([OP] VI): take the can (stepped phase by phase from its preview), then locate the
    box (the head turns to it)."""
    _, phases = stepped_from_the_preview(page, hrp2_console, "take_can")
    print("take_can stepped through:", phases)
    assert len(phases) >= 3 and phases[0] == "walk"  # (the tuck ran at once; then the walk, the grasp, ...)
    assert get_json(f"{hrp2_console.base}/api/recognitions")["recognitions"]["can"]["status"] == "held"
    playwright_api.expect(page.locator(".rec-pop")).to_have_count(0)
    run_from_the_page(page, hrp2_console, "locate_trash_box")
    playwright_api.expect(page.locator(".rec-pop")).to_have_count(1)  # the trash box's alone
    playwright_api.expect(page.locator(".rec-pop", has_text="trash_box at")).to_have_count(1)
    playwright_api.expect(page.locator("#camera-popups").get_by_role("button", name="Confirm")).to_have_count(1)
    popups_inside(page, "the trash box")
    shot(page, artifacts, "camera_can_taken")
    confirm_from_the_popup(page, hrp2_console, "trash_box")


def test_expo_from_the_page_throw_can_and_the_page_shows_it_landed_in_the_box(page, hrp2_console, artifacts):
    done = run_from_the_page(page, hrp2_console, "throw_can")
    landing = done["result"]["landing"]
    print("landing:", landing)
    assert landing["verdict"] == "in the box"  # (EXPO from rendered perception: 20 of 20 in the box)
    verdict = page.locator(".rec-pop.verdict")
    playwright_api.expect(verdict).to_contain_text(f"can: {landing['verdict']}")
    playwright_api.expect(verdict.get_by_role("button")).to_have_count(0)  # a verdict, not a question
    playwright_api.expect(page.locator("#history")).to_contain_text(f"it landed {landing['verdict']}")
    popups_inside(page, "the verdict")
    shot(page, artifacts, "camera_landing_verdict")
