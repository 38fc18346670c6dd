"""The operator page's layout (issue 29) in a real headless Chromium against a real `hrp2-console`: at 1280x800
and 1920x1080 no panel overlaps the 3D view or another panel and none is cut; viser's own panel is out of the way
with its E-STOP in sight; the capture-point error panel updates at >= 10 Hz and shows the run's time after a
reset. Every test saves a screenshot (HRP2_ARTIFACTS, else pytest's tmp dir), like test_operator_page.py."""

from __future__ import annotations

import os
import time

import playwright.sync_api as playwright_api
import pytest

from tests.browser import test_operator_page as op
from tests.browser.test_operator_page import post_json, released, shot, wait_until

# the operator page's fixtures, by name: its console, its Chromium page and where the screenshots go
hrp2_console, page, page_urls, artifacts = op.hrp2_console, op.page, op.page_urls, op.artifacts
saves_a_screenshot = op.saves_a_screenshot

pytestmark = pytest.mark.browser

SIZES = ((1280, 800), (1920, 1080))
DOC_SCREENSHOT = op.ROOT / "docs" / "img" / "operator_page_layout.png"  # written with HRP2_SAVE_PLOTS=1
#: the page's panels: the 3D view, the camera, each plot and the column of controls
PANELS = ("#view iframe", "#camera", "#plot-x", "#plot-y", "#plot-f", "#plot-cp-box", "#controls")
_BOXES = """(sels) => sels.map((s) => { const e = s.startsWith('#plot-') && !s.endsWith('-box')
    ? document.querySelector(s).parentElement : document.querySelector(s);
    const r = e.getBoundingClientRect(); return [s, r.left, r.top, r.right, r.bottom]; })"""
#: [Hz] the CP panel's redraws over CP_WINDOW_S: measured 8.9-13.5 Hz (5 runs) on this 2-core machine at load 6-12
#: with the 3D view drawn in software; the frames set the pace. Measured minus a margin is under the issue's 10 Hz,
#: so asserted at 10 Hz: a heavily loaded machine can fail it (docs/operator-page.md)
CP_PANEL_MIN_HZ = 10.0
CP_WINDOW_S = 5.0


def overlap(a, b) -> float:
    """The area [px^2] two (left, top, right, bottom) boxes share."""
    w = min(a[2], b[2]) - max(a[0], b[0])
    h = min(a[3], b[3]) - max(a[1], b[1])
    return max(0.0, w) * max(0.0, h)


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_no_panel_overlaps_the_3d_view_or_another_and_none_is_cut(page, artifacts, size):
    w, h = size
    page.set_viewport_size({"width": w, "height": h})
    try:
        page.wait_for_timeout(1500)  # laid out again, the canvases refitted and redrawn
        boxes = {s: tuple(b) for s, *b in page.evaluate(_BOXES, list(PANELS))}
        for s, (left, top, right, bottom) in boxes.items():
            assert left >= -0.5 and top >= -0.5 and right <= w + 0.5 and bottom <= h + 0.5, (s, boxes[s], size)
            assert right - left >= 100 and bottom - top >= 60, f"{s} is too small to read: {boxes[s]}"
        names = list(boxes)
        for i, a in enumerate(names):
            for b in names[i + 1:]:
                assert overlap(boxes[a], boxes[b]) <= 1.0, f"{a} {boxes[a]} overlaps {b} {boxes[b]} at {size}"
        # nothing of the monitor (camera and plots) scrolled out of sight: each legend's last line readable
        monitor = page.evaluate("(() => { const m = document.getElementById('monitor'); "
                                "return [m.scrollHeight, m.clientHeight, m.scrollWidth, m.clientWidth]; })()")
        assert monitor[0] <= monitor[1] + 1 and monitor[2] <= monitor[3] + 1, f"the monitor overflows: {monitor}"
        for legend in ("#legend-x", "#legend-y", "#legend-f", "#legend-cp"):
            box = page.locator(legend).bounding_box()
            assert box["y"] + box["height"] <= h + 0.5, (legend, box, size)
        playwright_api.expect(page.locator("#legend-cp")).to_contain_text("CP error x")
        # the 3D view: viser's main panel minimized, its E-STOP in a corner of the view (not over its middle)
        view = boxes["#view iframe"]
        frame = page.frame_locator("#view iframe")
        estop = frame.get_by_role("button", name="E-STOP", exact=True)
        playwright_api.expect(estop).to_be_visible(timeout=30_000)
        e = estop.bounding_box()
        assert e["x"] >= view[0] + (view[2] - view[0]) / 2 and e["y"] + e["height"] <= view[1] + 0.35 * (
            view[3] - view[1]), f"viser's E-STOP at {e}, the view {view}"
        playwright_api.expect(frame.get_by_text("follow the robot")).to_be_hidden()
        shot(page, artifacts, f"layout_{w}x{h}")
        if os.environ.get("HRP2_SAVE_PLOTS") == "1" and size == SIZES[0]:
            save_doc_screenshot(page, frame)
    finally:
        page.set_viewport_size({"width": 1280, "height": 800})


def save_doc_screenshot(page, frame) -> None:
    """docs/img/operator_page_layout.png: the page as laid out, viser's software-WebGL notice closed, in 128
    colours (a small file for the repository)."""
    from PIL import Image

    try:
        frame.locator(".mantine-Notification-closeButton").first.click(timeout=5_000)
        page.wait_for_timeout(500)
    except playwright_api.Error:
        pass
    DOC_SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(DOC_SCREENSHOT))
    img = Image.open(DOC_SCREENSHOT).convert("RGB")
    img.quantize(128, method=Image.Quantize.FASTOCTREE).save(DOC_SCREENSHOT, optimize=True)


def cp_counts(page) -> dict:
    return page.evaluate("({draws: hrp2Plots.cp.draws, samples: hrp2Plots.cp.samples, x: hrp2Plots.x.draws, "
                         "t: performance.now()})")


def test_the_cp_panel_updates_at_10_hz_or_more(page, artifacts):
    page.locator("#plot-cp-box").scroll_into_view_if_needed()
    wait_until(lambda: page.evaluate("hrp2Plots.cp.t.length") > 10, 20.0, "CP samples in the panel")
    a = cp_counts(page)
    page.wait_for_timeout(CP_WINDOW_S * 1000)
    b = cp_counts(page)
    dt = (b["t"] - a["t"]) / 1e3
    draws_hz, samples_hz = (b["draws"] - a["draws"]) / dt, (b["samples"] - a["samples"]) / dt
    print(f"CP panel: {draws_hz:.1f} redraws/s, {samples_hz:.1f} samples/s over {dt:.1f} s (the ZMP/COG x plot "
          f"{(b['x'] - a['x']) / dt:.1f} redraws/s)")
    assert draws_hz >= CP_PANEL_MIN_HZ and samples_hz >= CP_PANEL_MIN_HZ, (draws_hz, samples_hz)
    shot(page, artifacts, "cp_panel")


def test_after_a_reset_the_cp_panel_shows_the_new_runs_time(page, hrp2_console, artifacts):
    released(hrp2_console)
    c = hrp2_console
    # a run older than the panel's 10 s window: its old axis would not contain the new run's times
    wait_until(lambda: c.state()["time"] > 12.0, 30.0, "a run older than 12 s")
    old_t = page.evaluate("hrp2Plots.cp.t[hrp2Plots.cp.t.length - 1]")
    post_json(f"{c.base}/api/sim/reset", {"scene": c.state()["scene"]}, timeout=60.0)
    wait_until(lambda: c.state()["time"] < old_t, 30.0, "the new run's time")
    time.sleep(1.0)  # a few samples of the new run
    t_state = c.state()["time"]
    shown = wait_until(lambda: (p := page.evaluate("({t: hrp2Plots.cp.t, axis: hrp2Plots.cp.axis})"))["t"]
                       and p["t"][-1] >= t_state - 0.5 and p, 10.0, "the panel at the new run's time")
    t, axis = shown["t"], shown["axis"]
    assert 0.0 <= t[0] < t_state and t[-1] < t_state + 5.0, f"the panel's samples {t[0]:.2f}-{t[-1]:.2f} s, " \
        f"the run at {t_state:.2f} s (before the reset {old_t:.2f} s)"
    page.wait_for_timeout(300)  # drawn
    axis = page.evaluate("hrp2Plots.cp.axis")
    assert 0.0 <= axis["t0"] <= axis["t1"] < t_state + 5.0, axis
    assert all(0.0 <= s <= axis["t1"] for s in axis["ticks"]), axis
    legend_t = float(page.locator("#legend-cp").inner_text().rsplit("t ", 1)[1].split()[0])
    assert abs(legend_t - axis["t1"]) < 1.0 and legend_t < t_state + 5.0, (legend_t, axis)
    shot(page, artifacts, "cp_panel_after_reset")


def test_the_3d_views_own_estop_engages_the_hard_stop_with_its_panel_minimized(page, hrp2_console, artifacts):
    released(hrp2_console)
    frame = page.frame_locator("#view iframe")
    frame.get_by_role("button", name="E-STOP", exact=True).click()
    try:
        wait_until(lambda: hrp2_console.state()["emergency"]["hard_stop"], 10.0, "hard_stop after viser's E-STOP")
        playwright_api.expect(page.locator("#banner")).to_be_visible()
        shot(page, artifacts, "viser_estop_engaged")
    finally:
        post_json(f"{hrp2_console.base}/api/estop/release")
    wait_until(lambda: not hrp2_console.state()["emergency"]["hard_stop"], 5.0, "released")
