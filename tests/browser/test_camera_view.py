"""Perception in the camera view (issue 29) in a real headless Chromium against a real `hrp2-console` in the EXPO
scene, the EXPO task run through the API as a script would: the recognition pop-ups stay inside the camera frame
with their text whole (1280x800, 1920x1080, the frame resized), the can's pop-up goes once take_can holds it (no
second Confirm beside another), and after throw_can the page shows where the robot saw the can end. The console
runs without its 3D view (--headless: the camera is the page's own stream), which spares software WebGL's load.
Every test saves a screenshot (HRP2_ARTIFACTS, else pytest's tmp dir), like test_operator_page.py."""

from __future__ import annotations

from pathlib import Path

import playwright.sync_api as playwright_api
import pytest

from tests.browser import test_operator_page as op
from tests.browser.test_operator_page import get_json, post_json, shot, wait_until

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


def run_to_end(c: op.Console, behavior: str, params: dict | None = None) -> dict:
    run = post_json(f"{c.base}/api/behaviors/{behavior}", params or {})
    return wait_until(lambda: next((r for r in c.state()["runs"] if r["id"] == run["id"] and r["state"] != "running"),
                                   None), RUN_TIMEOUT_S, f"{behavior} to end", period=0.5)


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


def test_recognition_popups_stay_inside_the_camera_frame(page, hrp2_console, artifacts):
    post_json(f"{hrp2_console.base}/api/sim/reset", {"scene": "expo"}, timeout=60.0)
    wait_until(lambda: hrp2_console.state()["scene"] == "expo", 30.0, "the expo scene")
    done = run_to_end(hrp2_console, "locate_can")
    assert done["state"] == "succeeded", done["message"]
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


def test_the_taken_cans_popup_goes_and_one_confirm_remains(page, hrp2_console, artifacts):
    """In the EXPO trial's order ([OP] VI): take the can, then locate the box (the head turns to it)."""
    done = run_to_end(hrp2_console, "take_can")
    assert done["state"] == "succeeded", done["message"]
    assert get_json(f"{hrp2_console.base}/api/recognitions")["recognitions"]["can"]["status"] == "held"
    playwright_api.expect(page.locator(".rec-pop")).to_have_count(0)
    done = run_to_end(hrp2_console, "locate_trash_box")
    assert done["state"] == "succeeded", done["message"]
    playwright_api.expect(page.locator(".rec-pop")).to_have_count(1)  # the trash box's alone
    playwright_api.expect(page.locator(".rec-pop", has_text="trash_box at")).to_have_count(1)
    playwright_api.expect(page.locator("#camera-popups").get_by_role("button", name="Confirm")).to_have_count(1)
    popups_inside(page, "the trash box")
    shot(page, artifacts, "camera_can_taken")


def test_after_throw_can_the_page_shows_where_the_can_landed(page, hrp2_console, artifacts):
    done = run_to_end(hrp2_console, "throw_can")
    assert done["state"] == "succeeded", done["message"]
    landing = done["result"]["landing"]
    print("landing:", landing)
    assert landing["verdict"] in ("in the box", "out of the box")
    verdict = page.locator(".rec-pop.verdict")
    playwright_api.expect(verdict).to_contain_text(f"can: {landing['verdict']}")
    playwright_api.expect(verdict.get_by_role("button")).to_have_count(0)  # a verdict, not a question
    playwright_api.expect(page.locator("#history")).to_contain_text(f"it landed {landing['verdict']}")
    popups_inside(page, "the verdict")
    shot(page, artifacts, "camera_landing_verdict")
