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


#: The page's camera frames, plot samples and redraws (ZMP/COG x, and the CP-error panel) so far, its clock [ms].
_PAGE_COUNTS = """() => ({frames: window.hrp2Camera.frames, samples: hrp2Plots.x.samples, draws: hrp2Plots.x.draws,
                         cp_samples: hrp2Plots.cp.samples, cp_draws: hrp2Plots.cp.draws, t: performance.now()})"""


def count_messages(url: str, seconds: float, binary: bool, out: dict) -> None:
    """Messages per second a script receives on the WebSocket `url` (binary ones only, or text ones only)."""
    from websockets.sync.client import connect

    with connect(url, open_timeout=10, max_size=None) as ws:
        ws.recv(timeout=10)  # the stream is running
        n, t0 = 0, time.monotonic()
        while (now := time.monotonic()) - t0 < seconds:
            try:
                m = ws.recv(timeout=max(0.01, seconds - (now - t0)))
            except TimeoutError:
                break
            n += isinstance(m, bytes) == binary
        out[url] = n / (time.monotonic() - t0)


def measure_page_rates(page, console_base: str, seconds: float) -> dict[str, dict[str, float]]:
    """Over `seconds` of wall time, at once: what the console delivers to a script beside the page (the camera
    stream at 12 Hz, the telemetry at 25 Hz: the plots' data) and what the page shows (camera frames, samples its
    plots took in, their redraws, those of the CP-error panel) [Hz]. The page is the operator page, live."""
    import threading

    ws_base = console_base.replace("http://", "ws://")
    urls = {"camera": (f"{ws_base}/ws/camera?rate_hz=12", True), "telemetry": (f"{ws_base}/ws/telemetry?rate_hz=25",
                                                                                 False)}
    received: dict = {}
    scripts = [threading.Thread(target=count_messages, args=(url, seconds, binary, received))
               for url, binary in urls.values()]
    for t in scripts:
        t.start()
    a = page.evaluate(_PAGE_COUNTS)
    page.wait_for_timeout(seconds * 1000)
    b = page.evaluate(_PAGE_COUNTS)
    for t in scripts:
        t.join(timeout=20.0)
    dt = (b["t"] - a["t"]) / 1e3
    return {"delivered_hz": {name: received.get(url, 0.0) for name, (url, _) in urls.items()},
            "shown_hz": {"camera": (b["frames"] - a["frames"]) / dt, "plot_samples": (b["samples"] - a["samples"]) / dt,
                         "plot_draws": (b["draws"] - a["draws"]) / dt,
                         "cp_plot_samples": (b["cp_samples"] - a["cp_samples"]) / dt,
                         "cp_plot_draws": (b["cp_draws"] - a["cp_draws"]) / dt}}


def run_page_rates_bench(duration_s: float = 10.0, scene: str = "default") -> dict[str, Any]:
    """The `page-rates` scenario: a real console at real time and the operator page in Chromium (1280 x 800);
    the camera and plot rates delivered and shown over `duration_s` wall seconds (the issue asks the camera at
    >= 10 Hz and the plots at >= 20 Hz)."""
    from playwright.sync_api import sync_playwright

    from app.lab.console_process import Console

    chromium = os.environ.get("HRP2_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
    console = Console("--speed", "1.0", "--scene", scene, headless=False, viewer_port=_free_port())
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=chromium, headless=True, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.set_default_timeout(60_000)
            page.goto(f"http://127.0.0.1:{console.port}/", wait_until="domcontentloaded")
            page.wait_for_function("document.getElementById('conn').textContent.startsWith('live')")
            page.locator("#s-chain").click()  # the keys to the page, not to a field
            page.keyboard.press("Digit1")  # the right hand; W held: a stick streaming it forward, as the issue asks
            page.keyboard.down("KeyW")
            try:
                page.locator("#camera").scroll_into_view_if_needed()
                rates = measure_page_rates(page, f"http://127.0.0.1:{console.port}", duration_s)
                streamed = page.locator("#stream-state").inner_text()
            finally:
                page.keyboard.up("KeyW")
            browser.close()
    finally:
        console.stop()
    return {"scenario": "page-rates", "scene": scene, "duration_s": duration_s, **rates, "stick": streamed,
            "asked_hz": {"camera": 10.0, "plots": 20.0}}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_estop_browser_bench(clicks: int = 50, scene: str = "default") -> dict[str, Any]:
    """`clicks` E-STOP presses (pointer-down ... engaged at the loop, the robot's own monotonic stamp; the
    browser's event time on the epoch clock, converted); each released through the API before the next."""
    from playwright.sync_api import sync_playwright

    from app.lab.console_process import Console
    from app.lab.stats import percentiles_ms

    chromium = os.environ.get("HRP2_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
    console = Console("--speed", "1.0", "--scene", scene, headless=False, viewer_port=_free_port())
    latencies: list[float] = []
    input_delays: list[float] = []  # pointer-down -> the page's handler running (the page's own thread)
    streamed: list[int] = []
    answered_by: list[str] = []  # which way in answered first: "door", "stream" or "post"
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
                answered_by.append(reply.get("via") or ("stream" if reply.get("estop") else "post"))
                if reply.get("ok") and not reply.get("message", "").endswith("already engaged"):
                    engaged_epoch_ms = (reply["engaged_at_monotonic_s"] + epoch_minus_mono_s) * 1e3
                    latencies.append(engaged_epoch_ms - rec["event_epoch_ms"])
                    input_delays.append(rec["handled_epoch_ms"] - rec["event_epoch_ms"])
                streamed.append(1 if "streaming" in page.locator("#stream-state").inner_text() else 0)
                console.request("POST", "/api/estop/release", body={})
            browser.close()
    finally:
        console.stop()
    return {"scenario": "estop-browser", "scene": scene, "clicks": clicks,
            "pointerdown_to_engaged": percentiles_ms(latencies),
            "pointerdown_to_handler": percentiles_ms(input_delays),
            "clicks_while_streaming": sum(streamed),
            "answered_first_by": {k: answered_by.count(k) for k in sorted(set(answered_by))}}
