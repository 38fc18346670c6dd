"""Preview before motion on the operator page (real Chromium against a real console): a walk_to previewed from
its form shows its plan and the Run / Step / Cancel buttons with the ghost in the 3D view; Cancel leaves the robot
standing where it was, nothing started."""

from __future__ import annotations

import math
import re
from pathlib import Path

import playwright.sync_api as playwright_api
import pytest

from tests.browser.test_operator_page import (  # noqa: F401 - fixtures
    artifacts,
    hrp2_console,
    page,
    page_urls,
    released,
    saves_a_screenshot,
    shot,
)

pytestmark = pytest.mark.browser
DOC_SHOT = Path(__file__).resolve().parents[2] / "docs" / "img" / "preview_walk_to.png"
STILL_M = 0.01  # [m] the base moves less than this while a preview is shown and cancelled (standing sway: ~1 mm)


def test_a_previewed_walk_shows_its_plan_and_cancel_leaves_the_robot_where_it_was(page, hrp2_console, artifacts):
    released(hrp2_console)
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
    page.wait_for_timeout(1500)  # the 3D view draws the ghost (5 Hz)
    shot(page, artifacts, "preview_walk_to")
    if DOC_SHOT.parent.exists():
        page.screenshot(path=str(DOC_SHOT))
    panel.get_by_role("button", name="Cancel", exact=True).click()
    playwright_api.expect(panel).to_be_hidden()
    page.wait_for_timeout(1000)
    after = hrp2_console.state()
    assert len(after["runs"]) == runs_before  # nothing started
    moved = math.dist(before["base"]["pos"][:2], after["base"]["pos"][:2])
    assert moved < STILL_M, moved
