"""The `estop-browser` benchmark: E-STOP pointer-down in a real Chromium -> hard stop engaged in the loop, while
the page streams a stick (a stubbed gamepad with its dead-man held) and shows the 3D view. Needs the `test`
extra (playwright) and a Chromium (`make browser`)."""

from __future__ import annotations

import os
import shutil
import socket
import time
from typing import Any

CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
_STUB_GAMEPAD = """() => {
    const button = () => ({pressed: false, touched: false, value: 0});
    window.__pad = {id: "bench gamepad", index: 0, connected: true, mapping: "standard", timestamp: 0,
                    axes: [0, 0, 0, 0], buttons: Array.from({length: 17}, button)};
    window.__pad.buttons[5] = {pressed: true, touched: true, value: 1};  // the dead-man, held
    Object.defineProperty(navigator, "getGamepads", {configurable: true, value: () => [window.__pad]});
}"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_estop_browser_bench(clicks: int = 50, scene: str = "default") -> dict[str, Any]:
    """`clicks` E-STOP presses (pointer-down ... engaged at the loop, the robot's own monotonic stamp; the
    browser's event time on the epoch clock, converted); each released through the API before the next."""
    from playwright.sync_api import sync_playwright

    from app.console_process import Console
    from app.stats import percentiles_ms

    chromium = os.environ.get("HRP2_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
    console = Console("--speed", "1.0", "--scene", scene, headless=False, viewer_port=_free_port())
    latencies: list[float] = []
    streamed: list[int] = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=chromium, headless=True, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.set_default_timeout(60_000)
            page.goto(f"http://127.0.0.1:{console.port}/", wait_until="domcontentloaded")
            page.wait_for_function("document.getElementById('conn').textContent.startsWith('live')")
            page.wait_for_function("document.querySelectorAll('#view iframe').length === 1")
            page.evaluate(_STUB_GAMEPAD)
            page.get_by_role("radio", name="head").click()
            box = page.locator("#estop").bounding_box()
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            for k in range(clicks):
                page.evaluate(f"() => {{ window.__pad.axes[2] = {0.5 if (k // 5) % 2 else -0.5}; }}")  # yaw to and fro
                time.sleep(0.3)  # the stream runs
                n = page.evaluate("window.hrp2Estops.length")
                page.mouse.click(x, y)
                page.wait_for_function(f"window.hrp2Estops.length > {n} && window.hrp2Estops[{n}].reply !== null")
                rec = page.evaluate(f"window.hrp2Estops[{n}]")
                epoch_minus_mono_s = time.time() - time.monotonic()
                reply = rec["reply"]
                if reply.get("ok") and not reply.get("message", "").endswith("already engaged"):
                    latencies.append((reply["engaged_at_monotonic_s"] + epoch_minus_mono_s) * 1e3
                                     - rec["event_epoch_ms"])
                streamed.append(1 if "streaming" in page.locator("#stream-state").inner_text() else 0)
                console.request("POST", "/api/estop/release", body={})
            browser.close()
    finally:
        console.stop()
    return {"scenario": "estop-browser", "scene": scene, "clicks": clicks,
            "pointerdown_to_engaged": percentiles_ms(latencies),
            "clicks_while_streaming": sum(streamed)}
