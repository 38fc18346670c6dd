"""The operator page in a real headless Chromium, against a real `hrp2-console` (simulation, HTTP API and
the viser 3D view) started in a subprocess: what an operator sees and what their clicks do."""

from __future__ import annotations

import json
import os
import queue
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import playwright.sync_api as playwright_api  # pinned in the `test` extra; drives Debian's chromium, no download
import pytest

pytestmark = pytest.mark.browser


ROOT = Path(__file__).resolve().parents[2]
CHROMIUM = os.environ.get("HRP2_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]  # headless and a fresh temporary --user-data-dir are playwright's defaults for launch()
SCREENSHOT = ROOT / "docs" / "img" / "operator_page.png"
JOINT = "RARM_JOINT0"
TARGET_DEG = -30.0


def console() -> list[str]:
    script = Path(sys.executable).with_name("hrp2-console")
    if script.exists():
        return [str(script)]
    found = shutil.which("hrp2-console")
    return [found] if found else [sys.executable, "-m", "app.cli"]


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def get_json(url: str, timeout: float = 2.0) -> dict:
    with urllib.request.urlopen(url, timeout=timeout) as r:
        return json.loads(r.read())


def wait_until(predicate, timeout: float, what: str, period: float = 0.1):
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline:
        last = predicate()
        if last:
            return last
        time.sleep(period)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what} (last: {last!r})")


class Console:
    def __init__(self, proc: subprocess.Popen, base: str, viewer_port: int, output: list[str]):
        self.proc, self.base, self.viewer_port, self.output = proc, base, viewer_port, output

    def state(self) -> dict:
        return get_json(f"{self.base}/api/state")


@pytest.fixture(scope="module")
def hrp2_console():
    """`hrp2-console --port 0 --viewer-port <free> --speed 1.0` (with the viser view), up and answering."""
    if not Path(CHROMIUM).exists():
        pytest.skip(f"no Chromium at {CHROMIUM} (`make browser` installs Debian's)")
    proc = subprocess.Popen(
        [*console(), "--port", "0", "--viewer-port", str(free_port()), "--speed", "1.0"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    output: list[str] = []
    lines: queue.Queue[str] = queue.Queue()

    def pump() -> None:  # keep draining the pipe so that the console never blocks on a full one
        for line in proc.stdout:
            output.append(line)
            lines.put(line)

    threading.Thread(target=pump, name="console-stdout", daemon=True).start()
    try:
        http_port = viewer_port = None
        deadline = time.monotonic() + 30.0
        while (http_port is None or viewer_port is None) and time.monotonic() < deadline:
            if proc.poll() is not None:
                break
            try:
                line = lines.get(timeout=0.2)
            except queue.Empty:
                continue
            if m := re.search(r"operator page\s+http://[^:]+:(\d+)/", line):
                http_port = int(m.group(1))
            if m := re.search(r"3D viewer\s+http://[^:]+:(\d+)/", line):
                viewer_port = int(m.group(1))
        assert http_port and viewer_port, "the console did not start:\n" + "".join(output)
        c = Console(proc, f"http://127.0.0.1:{http_port}", viewer_port, output)

        def answers():
            try:
                return c.state()
            except OSError:
                return None

        wait_until(answers, 15.0, "GET /api/state")
        yield c
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)


@pytest.fixture(scope="module")
def page(hrp2_console):
    with playwright_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        try:
            pg = browser.new_page(viewport={"width": 1280, "height": 800})
            # Software WebGL (SwiftShader) renders the viser iframe in the same renderer and GPU process: while
            # it builds the scene, input events can stall for ~20 s on a 2-CPU machine, so actions wait longer.
            pg.set_default_timeout(40_000)
            playwright_api.expect.set_options(timeout=15_000)
            pg.goto(f"{hrp2_console.base}/", wait_until="domcontentloaded")
            yield pg
        finally:
            browser.close()


def shown_time(pg) -> float:
    """The simulated time as the state readout shows it: '12.345 s (tick 6172)'."""
    text = pg.locator("#s-time").inner_text()
    m = re.match(r"\s*(-?\d+(?:\.\d+)?) s", text)
    assert m, f"the time readout shows {text!r}"
    return float(m.group(1))


def test_the_state_readout_updates(page):
    page.wait_for_function("/^\\d+\\.\\d+ s/.test(document.getElementById('s-time').textContent)")
    t0 = shown_time(page)
    time.sleep(0.5)
    # the page polls every 0.2 s; allow for the viser iframe's software-WebGL start-up stall
    wait_until(lambda: shown_time(page) > t0 + 0.2, 20.0, f"the shown time to advance past {t0} s", period=0.2)
    assert page.locator("#s-chain").inner_text().strip() not in ("", "-")
    assert page.locator("#s-hard").inner_text() == "off"


def test_estop_click_engages_the_hard_stop_and_release_clears_it(page, hrp2_console):
    estop = page.get_by_role("button", name="E-STOP", exact=True)
    playwright_api.expect(estop).to_be_visible()
    box = estop.bounding_box()
    assert box and box["height"] >= 50, f"the E-STOP button is not big: {box}"

    estop.click()
    wait_until(lambda: hrp2_console.state()["emergency"]["hard_stop"], 5.0, "hard_stop == true in /api/state")
    playwright_api.expect(page.locator("#s-hard")).to_have_text("ENGAGED")
    playwright_api.expect(page.locator("#s-hard")).to_have_class(re.compile(r"\balarm\b"))

    page.get_by_role("button", name="Release e-stop").click()
    wait_until(lambda: not hrp2_console.state()["emergency"]["hard_stop"], 5.0, "hard_stop == false")
    playwright_api.expect(page.locator("#s-hard")).to_have_text("off")


def test_the_joint_form_moves_the_commanded_angle(page, hrp2_console):
    assert not hrp2_console.state()["emergency"]["hard_stop"]
    before = hrp2_console.state()["joints"][JOINT]["cmd_deg"]
    assert abs(before - TARGET_DEG) > 5.0, f"{JOINT} already at {before} deg"
    page.get_by_label("joint").select_option(JOINT)
    page.get_by_label("angle [deg]").fill(str(TARGET_DEG))
    page.get_by_label("time [s]").fill("1")
    page.get_by_role("button", name="Send").click()
    playwright_api.expect(page.locator("#message")).to_contain_text("interpolating")

    def reached():
        cmd = hrp2_console.state()["joints"][JOINT]["cmd_deg"]
        return abs(cmd - TARGET_DEG) < 1.0 and cmd

    wait_until(reached, 8.0, f"{JOINT} cmd_deg -> {TARGET_DEG}")


def post_json(url: str, body: dict | None = None, timeout: float = 5.0) -> dict:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, method="POST", headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=timeout) as r:
        return json.loads(r.read())


def test_stop_motion_and_release_motion_next_to_the_estop(page, hrp2_console):
    stop = page.get_by_role("button", name="Stop motion", exact=True)
    release = page.get_by_role("button", name="Release motion", exact=True)
    playwright_api.expect(stop).to_be_visible()
    playwright_api.expect(release).to_be_visible()
    estop_box, stop_box = page.locator("#estop").bounding_box(), stop.bounding_box()
    assert stop_box["y"] - (estop_box["y"] + estop_box["height"]) < 100, "Stop motion is not next to the E-STOP"
    playwright_api.expect(page.locator("#s-motion")).to_have_text("off")
    playwright_api.expect(page.locator("#s-walkstop")).to_have_text("off")
    playwright_api.expect(page.locator("#s-ststop")).to_have_text("running")
    try:
        stop.click()
        wait_until(lambda: hrp2_console.state()["emergency"]["motion_stop"], 5.0, "motion_stop == true")
        playwright_api.expect(page.locator("#s-motion")).to_contain_text("STOPPED (operator")
        playwright_api.expect(page.locator("#s-motion")).to_have_class(re.compile(r"\balarm\b"))
        assert not hrp2_console.state()["emergency"]["hard_stop"]  # balance keeps working
        release.click()
        wait_until(lambda: not hrp2_console.state()["emergency"]["motion_stop"], 5.0, "motion_stop == false")
        playwright_api.expect(page.locator("#s-motion")).to_have_text("off")
    finally:
        if hrp2_console.state()["emergency"]["motion_stop"]:
            post_json(f"{hrp2_console.base}/api/motion/release")


def test_a_stopped_stabilizer_is_shown(page, hrp2_console):
    post_json(f"{hrp2_console.base}/api/stabilizer/stop")
    try:
        wait_until(lambda: hrp2_console.state()["emergency"]["stabilizer_stop"], 5.0, "stabilizer_stop == true")
        playwright_api.expect(page.locator("#s-ststop")).to_have_text("STOPPED")
        playwright_api.expect(page.locator("#s-ststop")).to_have_class(re.compile(r"\balarm\b"))
    finally:
        post_json(f"{hrp2_console.base}/api/stabilizer/start")
    wait_until(lambda: not hrp2_console.state()["emergency"]["stabilizer_stop"], 5.0, "stabilizer_stop == false")
    playwright_api.expect(page.locator("#s-ststop")).to_have_text("running")


def test_the_viser_view_loads_with_a_canvas(page, hrp2_console):
    iframe = page.locator("#view iframe")
    playwright_api.expect(iframe).to_have_attribute("src", re.compile(rf":{hrp2_console.viewer_port}/$"))
    frame = page.frame_locator("#view iframe")
    playwright_api.expect(frame.locator("#root")).to_be_attached(timeout=15_000)
    webgl = page.evaluate("!!document.createElement('canvas').getContext('webgl2')")
    if not webgl:
        pytest.skip("no WebGL in this headless Chromium: only the viser page's #root was checked")
    canvas = frame.locator("canvas").first
    playwright_api.expect(canvas).to_be_visible(timeout=15_000)
    box = canvas.bounding_box()
    assert box and box["width"] > 100 and box["height"] > 100, f"the 3D canvas is tiny: {box}"

    if os.environ.get("HRP2_SAVE_PLOTS") == "1":
        page.wait_for_timeout(2000)  # let viser stream the meshes in
        try:  # viser's "Software WebGL rendering detected" toast would cover the view in the docs image
            close = frame.locator(".mantine-Notification-closeButton").first
            close.click(timeout=10_000)
            close.wait_for(state="detached", timeout=5_000)
        except playwright_api.Error:
            pass
        SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(SCREENSHOT))
