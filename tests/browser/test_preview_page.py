"""Preview before motion on the operator page (real Chromium against a real console): a walk_to previewed from
its form shows its plan and the Run / Step / Cancel buttons with the ghost in the 3D view; Cancel leaves the robot
standing where it was, nothing started; Run walks the footsteps it showed (within 1 cm)."""

from __future__ import annotations

import io
import math
import os
import re
from pathlib import Path

import playwright.sync_api as playwright_api
import pytest

from tests.browser import test_operator_page as op
from tests.browser.test_operator_page import released, shot

# the operator page's fixtures, by name: its console, its Chromium page and where the screenshots go
hrp2_console, page, page_urls, artifacts = op.hrp2_console, op.page, op.page_urls, op.artifacts
saves_a_screenshot = op.saves_a_screenshot

pytestmark = pytest.mark.browser
DOC_SHOT = Path(__file__).resolve().parents[2] / "docs" / "img" / "preview_walk_to.png"  # HRP2_SAVE_PLOTS=1
#: [px] more of the 3D view in the ghost's pink once it is drawn: measured +44 (1280x800, software WebGL)
GHOST_MIN_PIXELS = 20
STILL_M = 0.01  # [m] the base moves less than this while a preview is shown and cancelled (standing sway: ~1 mm)
MATCH_M = 0.01  # [m] the done-when's bound between the footsteps shown and the ones walked


def ghost_pixels(page) -> int:
    """Pixels of the 3D view in the ghost's colours (app/console/viewer_preview.py: pink, unlit lines)."""
    from PIL import Image

    img = Image.open(io.BytesIO(page.locator("#view iframe").screenshot())).convert("RGB")
    return sum(1 for r, g, b in img.getdata() if r > 215 and 30 < g < 160 and 130 < b < 240)


def test_a_previewed_walk_shows_its_plan_and_cancel_leaves_the_robot_where_it_was(page, hrp2_console, artifacts):
    released(hrp2_console)
    frame = page.frame_locator("#view iframe")
    playwright_api.expect(frame.locator("canvas[data-engine]").first).to_be_visible(timeout=30_000)
    page.wait_for_timeout(3000)  # viser streams the meshes in
    try:  # viser's "Software WebGL rendering detected" toast covers a corner of the view
        frame.locator(".mantine-Notification-closeButton").first.click(timeout=5_000)
    except playwright_api.Error:
        pass
    pink_before = ghost_pixels(page)
    before = hrp2_console.state()
    runs_before = len(before["runs"])
    page.locator("#behaviors").get_by_role("button", name="walk_to", exact=True).click()
    form = page.locator("#behavior-form")
    form.get_by_label("x_m").fill("0.6")
    form.get_by_label("y_m").fill("0.2")
    form.get_by_role("button", name="Preview").click()
    panel = page.locator("#preview")
    playwright_api.expect(panel).to_be_visible()
    playwright_api.expect(panel).to_contain_text(re.compile(r"walk_to: \d+ footsteps"))
    for name in ("Run", "Step", "Cancel"):
        playwright_api.expect(panel.get_by_role("button", name=name, exact=True)).to_be_visible()
    page.wait_for_timeout(2000)  # the 3D view draws the ghost (updated at 5 Hz)
    pink = ghost_pixels(page)
    print(f"ghost pixels: {pink_before} before the preview, {pink} with it")
    shot(page, artifacts, "preview_walk_to")
    assert pink > pink_before + GHOST_MIN_PIXELS, (pink_before, pink)
    if os.environ.get("HRP2_SAVE_PLOTS") == "1":
        page.screenshot(path=str(DOC_SHOT))
    panel.get_by_role("button", name="Cancel", exact=True).click()
    playwright_api.expect(panel).to_be_hidden()
    page.wait_for_timeout(1000)
    after = hrp2_console.state()
    assert len(after["runs"]) == runs_before  # nothing started
    moved = math.dist(before["base"]["pos"][:2], after["base"]["pos"][:2])
    assert moved < STILL_M, moved


def test_a_previewed_walk_run_from_the_preview_walks_the_footsteps_it_showed(page, hrp2_console, artifacts):
    c = hrp2_console
    released(c)
    page.locator("#behaviors").get_by_role("button", name="walk_to", exact=True).click()
    form = page.locator("#behavior-form")
    form.get_by_label("x_m").fill("0.3")
    form.get_by_label("y_m").fill("-0.1")
    with page.expect_response(re.compile(r"/api/behaviors/walk_to/preview$")) as answer:
        form.get_by_role("button", name="Preview").click()
    shown = answer.value.json()["footsteps"]  # what the page drew (its ghost, its text): the support foot first
    panel = page.locator("#preview")
    playwright_api.expect(panel).to_contain_text(f"walk_to: {len(shown) - 1} footsteps")
    panel.get_by_role("button", name="Run", exact=True).click()
    walking = op.wait_until(lambda: (f := op.get_json(f"{c.base}/api/walk/footsteps"))["walking"] and f, 10.0,
                            "the walk to start")
    # the AutoBalancer's plan as it starts (the footsteps not landed yet: one may be under way)
    planned = walking["footsteps"]
    tail = shown[len(shown) - len(planned):]
    assert [s["side"] for s in tail] == ["right" if f["leg"] == "rleg" else "left" for f in planned]
    off_m = max(math.hypot(s["x_m"] - f["pos"][0], s["y_m"] - f["pos"][1]) for s, f in zip(tail, planned, strict=True))
    print(f"{len(shown)} footsteps shown, {len(planned)} planned when the walk started; largest offset "
          f"{off_m * 1e3:.2f} mm")
    assert off_m <= MATCH_M, off_m
    run = op.wait_until(lambda: next((r for r in c.state()["runs"] if r["behavior"] == "walk_to"
                                      and r["state"] != "running"), None), 60.0, "walk_to to end")
    assert run["state"] == "succeeded", run["message"]
    playwright_api.expect(panel).to_be_hidden()  # the preview closes with its run
    shot(page, artifacts, "preview_walk_to_walked")
