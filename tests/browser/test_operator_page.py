"""The operator page in a real headless Chromium, against a real `hrp2-console` (simulation, HTTP API and
the viser 3D view) started in a subprocess: what an operator sees and what their clicks, keys, sticks and
gamepad do, checked in /api/state. Every test saves a screenshot (HRP2_ARTIFACTS, else pytest's tmp dir)."""

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
import urllib.error
import urllib.request
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

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
# [m] BODY travel from the walking stop to standing, walking at 0.1 m/s (a step ~0.08 m): measured 0.04-0.06 m
WALK_STOP_TRAVEL_M = 0.10
#: [s] from the page's release to the robot's tick that applied its zero (zeroed_within's upper bound), with the
#: robot's dead-man lengthened to DEADMAN_LONG_S so that only the page's own zero can pass it: the issue's 0.25 s.
#: Measured (stick, keys, touch, gamepad): 62-115 ms idle; 32-236 ms in 11 of 12 let-goes with two busy processes
#: beside the browser and the console on this 2-core machine, one 440 ms.
ZERO_WITHIN_S = 0.25
DEADMAN_LONG_S = 3.0  # [s] the dead-man's timeout while a test times the page's zero (default 0.2 s)


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

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5)


@pytest.fixture(scope="module")
def hrp2_console():
    """`hrp2-console --port 0 --viewer-port <free> --speed 1.0` (with the viser view), up and answering."""
    if not Path(CHROMIUM).exists():
        pytest.skip(f"no Chromium at {CHROMIUM} (`make browser` installs Debian's)")
    c = start_console(["--port", "0", "--viewer-port", str(free_port())])
    try:
        yield c
    finally:
        c.stop()


def start_console(args: list[str]) -> Console:
    proc = subprocess.Popen(
        [*console(), *args, "--speed", "1.0"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1,
        env={**os.environ, "PYTHONUNBUFFERED": "1", "HRP2_TEST_HOOKS": "1"})  # POST /api/sim/fault
    output: list[str] = []
    lines: queue.Queue[str] = queue.Queue()

    def pump() -> None:  # keep draining the pipe so that the console never blocks on a full one
        for line in proc.stdout:
            output.append(line)
            lines.put(line)

    threading.Thread(target=pump, name="console-stdout", daemon=True).start()
    try:
        http_port = viewer_port = None
        deadline = time.monotonic() + 90.0  # a loaded 2-CPU machine starts it slowly
        headless = "--headless" in args
        while (http_port is None or (viewer_port is None and not headless)) and time.monotonic() < deadline:
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
        assert http_port and (viewer_port or headless), "the console did not start:\n" + "".join(output)
        c = Console(proc, f"http://127.0.0.1:{http_port}", viewer_port, output)

        def answers():
            try:
                return c.state()
            except OSError:
                return None

        wait_until(answers, 60.0, "GET /api/state")
        return c
    except BaseException:
        Console(proc, "", 0, output).stop()
        raise


@pytest.fixture(scope="module")
def page_urls() -> list[str]:
    """Every URL the module's page (and its 3D view's iframe) asked for: requests and WebSockets."""
    return []


@pytest.fixture(scope="module")
def page(hrp2_console, page_urls):
    with playwright_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        try:
            pg = browser.new_page(viewport={"width": 1280, "height": 800})
            pg.on("request", lambda r: page_urls.append(r.url))
            pg.on("websocket", lambda ws: page_urls.append(ws.url))
            pg.failed_answers = []  # every answer of 400 or more the page was given ("404 http://..."), as it came
            pg.on("response", lambda r: r.status >= 400 and pg.failed_answers.append(f"{r.status} {r.url}"))
            pg.on("console", lambda m: m.type in ("error", "warning") and print(f"[page {m.type}] {m.text[:300]}"))
            pg.on("pageerror", lambda e: print(f"[page error] {e}"))
            # Software WebGL (SwiftShader) renders the viser iframe in the same renderer and GPU process: while
            # it builds the scene, input events can stall for ~20 s on a 2-CPU machine, so actions wait longer.
            pg.set_default_timeout(40_000)
            playwright_api.expect.set_options(timeout=15_000)
            pg.goto(f"{hrp2_console.base}/", wait_until="domcontentloaded")
            playwright_api.expect(pg.locator("#conn")).to_contain_text("live", timeout=30_000)
            yield pg
        finally:
            browser.close()


@pytest.fixture(scope="module")
def artifacts(tmp_path_factory) -> Path:
    """Where the screenshots go: $HRP2_ARTIFACTS (the CI keeps it) or pytest's temporary directory."""
    out = Path(os.environ["HRP2_ARTIFACTS"]) if os.environ.get("HRP2_ARTIFACTS") else tmp_path_factory.mktemp("shots")
    out.mkdir(parents=True, exist_ok=True)
    return out


@pytest.fixture(autouse=True)
def saves_a_screenshot(request, artifacts):
    """Every browser test that passes has saved at least one screenshot in `artifacts`."""
    started = time.time()
    yield
    report = getattr(request.node, "rep_call", None)
    if report is not None and report.passed:
        saved = [p.name for p in artifacts.glob("*.png") if p.stat().st_mtime >= started]
        assert saved, f"{request.node.name} saved no screenshot in {artifacts}"
    elif report is not None and report.failed and "page" in request.fixturenames:
        # what the page showed and what the console said when it failed (a CI run keeps the folder)
        try:
            request.getfixturevalue("page").screenshot(path=str(artifacts / f"FAILED_{request.node.name}.png"))
        except Exception as exc:  # noqa: BLE001 - the failure itself is what the report shows
            print(f"no screenshot of the failure: {exc}")
        c = request.getfixturevalue("hrp2_console")
        print("the console's last output:\n" + "".join(c.output[-40:]))


def shot(pg, artifacts: Path, name: str) -> Path:
    path = artifacts / f"{name}.png"
    pg.screenshot(path=str(path))
    return path


def post_json(url: str, body: dict | None = None, timeout: float = 5.0, client: str | None = None) -> dict:
    data = None if body is None else json.dumps(body).encode()
    headers = {"Content-Type": "application/json", **({"X-Client-Id": client} if client else {})}
    req = urllib.request.Request(url, data=data, method="POST", headers=headers)
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return json.loads(r.read())
    except urllib.error.HTTPError as exc:  # say what the console answered
        raise AssertionError(f"POST {url}: {exc.code} {exc.read().decode(errors='replace')}") from None


def released(c: Console) -> None:
    """The hard stop off (released through the API if a test left it on; a robot a failed test left fallen is
    reset, so that one failure does not fail the tests after it)."""
    if c.state()["fallen"]:
        post_json(f"{c.base}/api/sim/reset", {"scene": c.state()["scene"]}, timeout=60.0)
        wait_until(lambda: not c.state()["fallen"], 30.0, "standing after the reset")
    if c.state()["emergency"]["hard_stop"]:
        post_json(f"{c.base}/api/estop/release")
    wait_until(lambda: not c.state()["emergency"]["hard_stop"], 5.0, "hard_stop == false")
    # and its release blend over: until then the chain holds, and nothing operated moves (recover_time_s 2.5 s)
    wait_until(lambda: not c.state()["layers"]["hes"]["recovering"], 10.0, "hes recovering == false")


def motion(c: Console, point: str) -> list[float]:
    """The operator's twist at `point` after the dead-man, as the operation layer applies it (vx, vy, vz, wx..)."""
    return c.state()["operation"]["points"][point]["motion"]


@pytest.fixture
def deadman_lengthened(hrp2_console):
    """The robot's dead-man set to DEADMAN_LONG_S: a zero before that comes from the page (its release sends
    one), not from the stream going quiet (0.2 s + 0.1 s ramp by default, which alone would pass the bound)."""
    url = f"{hrp2_console.base}/api/operator/params"
    before = get_json(url)["params"]["deadman_timeout_s"]
    put_json(url, {"deadman_timeout_s": DEADMAN_LONG_S})
    try:
        yield
    finally:
        put_json(url, {"deadman_timeout_s": before})


def let_go_timer(c: Console, page) -> float:
    """Forget the page's last let-go and read the control time [s] now: call it just before letting go."""
    page.evaluate("window.hrp2LetGo = null")
    return c.state()["time"]


def zeroed_within(c: Console, page, point: str, t_before: float, timeout: float = 5.0) -> float:
    """How long [s] from the page's let-go of `point` to the robot's tick that applied its zero, at most: the smaller
    of two upper bounds, the page's round trip from sending the zero (in its release handler) to the robot's answer
    (window.hrp2LetGo), and the control time from `t_before` (let_go_timer's, read before the let-go: it includes the
    browser's input handling) to the tick the answer names. No polling of the state loads the console meanwhile:
    polled, the state's answers took up to 0.7 s under a CI run's load and made the bound fail while the robot had
    applied the zero within 15 ms. The state then shows the twist zero."""
    letgo = wait_until(lambda: page.evaluate(f"(() => {{ const r = window.hrp2LetGo; "
                                             f"return r && r.point === '{point}' && r; }})()"), timeout,
                       f"the page's let-go of {point} answered")
    reply = letgo["reply"]
    assert reply.get("ok") and reply.get("point") == point, reply
    wait_until(lambda: not any(motion(c, point)), timeout, f"the {point} twist zero in the state", period=0.05)
    round_trip_s = (letgo["answered_ms"] - letgo["sent_ms"]) * 1e-3
    from_before_s = reply["time_s"] - t_before
    print(f"{point} zeroed within {min(round_trip_s, from_before_s) * 1e3:.0f} ms of the release (round trip "
          f"{round_trip_s * 1e3:.0f} ms, from before the let-go {from_before_s * 1e3:.0f} ms)")  # (the figures, -s)
    return min(round_trip_s, from_before_s)


def test_the_page_loads_and_the_robot_is_drawn(page, hrp2_console, artifacts):
    from PIL import Image

    iframe = page.locator("#view iframe")
    playwright_api.expect(iframe).to_have_attribute("src", re.compile(rf"/viewer/\?websocket=.*"
                                                                  rf"{hrp2_console.viewer_port}"))
    frame = page.frame_locator("#view iframe")
    canvas = frame.locator("canvas[data-engine]").first
    playwright_api.expect(canvas).to_be_visible(timeout=30_000)
    page.wait_for_timeout(3000)  # viser streams the meshes in
    try:  # viser's "Software WebGL rendering detected" toast covers a corner of the view
        frame.locator(".mantine-Notification-closeButton").first.click(timeout=5_000)
    except playwright_api.Error:
        pass
    path = artifacts / "page_loaded.png"

    def drawn():
        page.locator("#view").screenshot(path=str(path))
        img = Image.open(path).convert("L")
        w, h = img.size
        # the robot stands in the middle of the view: that region is not one flat floor colour
        centre = img.crop((w // 3, h // 4, 2 * w // 3, 3 * h // 4))
        hist = centre.histogram()
        dark = sum(hist[:120]) / (centre.size[0] * centre.size[1])  # the robot's shaded links and feet
        return dark > 0.005 and len([n for n in hist if n]) > 40 and (dark, len([n for n in hist if n]))

    wait_until(drawn, 60.0, "the robot drawn in the 3D view (dark pixels in its centre)", period=1.0)
    if os.environ.get("HRP2_SAVE_PLOTS") == "1":
        SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(SCREENSHOT))
    shot(page, artifacts, "page")


LOOPBACK_NAMES = {"127.0.0.1", "localhost", "::1"}


def leaving(urls: list[str], ports: set[int]) -> list[str]:
    """The URLs that go anywhere but this machine's console: another host, or a port not in `ports` (blob: URLs
    are judged by the origin that made them; data: and about: load nothing)."""
    out = []
    for url in urls:
        u = urlsplit(url)
        if u.scheme in ("data", "about"):
            continue
        if u.scheme == "blob":
            u = urlsplit(url[len("blob:"):])
        if u.hostname not in LOOPBACK_NAMES or u.port not in ports:
            out.append(url)
    return out


def test_every_request_of_the_page_and_its_3d_view_stays_on_this_machine(page, hrp2_console, page_urls, artifacts):
    """What the page and its 3D view asked for: the page's requests and WebSockets (Playwright's events), and
    every resource each frame fetched (its Resource Timing entries: the 3D view's iframe runs in another
    process, whose requests Playwright does not report) and the 3D view's websocket address. None of the page's
    own was refused (a 404 for a favicon the page never named, once)."""
    http_port = int(hrp2_console.base.rsplit(":", 1)[1])
    ports = {http_port, hrp2_console.viewer_port, get_json(f"{hrp2_console.base}/api/config")["estop_port"]}
    frame = page.frame_locator("#view iframe")
    playwright_api.expect(frame.locator("canvas[data-engine]").first).to_be_visible(timeout=30_000)
    urls = list(page_urls)
    for f in page.frames:
        urls += [f.url, *f.evaluate("performance.getEntriesByType('resource').map((e) => e.name)")]
    src = page.locator("#view iframe").get_attribute("src")
    viewer_ws = parse_qs(urlsplit(src).query)["websocket"][0]
    urls.append(viewer_ws)
    paths = {urlsplit(u).path for u in urls}
    expected = {"/", "/static/js/estop.js", "/static/console.js", "/static/js/sticks.js", "/api/config",
                "/ws/telemetry", "/viewer/"}
    assert expected <= paths, sorted(paths)
    assert urlsplit(viewer_ws).port == hrp2_console.viewer_port
    assert not leaving(urls, ports), leaving(urls, ports)
    assert page.failed_answers == []
    shot(page, artifacts, "page_local_requests")


def test_the_api_docs_render_offline_from_the_console_alone(page, hrp2_console, artifacts):
    port = int(hrp2_console.base.rsplit(":", 1)[1])
    seen: list[str] = []
    refused: list[str] = []

    def only_here(route) -> None:  # anything for elsewhere is refused, and the test says what it was
        url = route.request.url
        seen.append(url)
        if leaving([url], {port}):
            refused.append(url)
            route.abort()
        else:
            route.continue_()

    ctx = page.context.browser.new_context(viewport={"width": 1280, "height": 800})
    try:
        ctx.route("**/*", only_here)
        docs = ctx.new_page()
        docs.set_default_timeout(40_000)
        t0 = time.monotonic()
        docs.goto(f"{hrp2_console.base}/docs", wait_until="domcontentloaded")
        # Swagger UI builds the page from the whole OpenAPI document (280 kB, 79 operations) in JavaScript: 3.3 s
        # in a browser of its own, 7-14 s beside the operator page (its 3D view drawn in software), over 15 s in
        # a CI run (the title was there when the assertion reported). So the page's 40 s, not expect's 15 s.
        playwright_api.expect(docs.locator(".swagger-ui .info .title")).to_contain_text("HRP-2 operator console",
                                                                                         timeout=40_000)
        print(f"/docs rendered its title {time.monotonic() - t0:.2f} s after the request")
        estop = docs.locator(".opblock-post", has=docs.locator(".opblock-summary-path", has_text=re.compile(
            r"^/api/estop$")))
        playwright_api.expect(estop).to_be_visible()
        assert docs.locator(".opblock").count() >= 40  # every route of the API, not an empty shell
        shot(docs, artifacts, "api_docs")
    finally:
        ctx.close()
    assert not refused, f"/docs asked for something off this machine: {refused}"
    paths = {urlsplit(u).path for u in seen}
    assert {"/docs", "/openapi.json", "/static/swagger-ui/swagger-ui-bundle.js"} <= paths, sorted(paths)


def test_the_estop_stays_visible_after_scrolling_to_the_bottom(page, artifacts):
    page.locator("#controls").evaluate("e => e.scrollTop = e.scrollHeight")
    page.evaluate("window.scrollTo(0, document.body.scrollHeight)")
    page.locator("#message").scroll_into_view_if_needed()
    estop = page.get_by_role("button", name="E-STOP", exact=True)
    playwright_api.expect(estop).to_be_in_viewport()
    box = estop.bounding_box()
    assert box["y"] >= 0 and box["y"] + box["height"] <= 800
    assert box["height"] >= 0.10 * 800, f"the E-STOP is {box['height']} px high, under 10 % of the page's 800"
    shot(page, artifacts, "scrolled_to_bottom")


def test_estop_click_engages_the_hard_stop_the_banner_shows_and_release_works(page, hrp2_console, artifacts):
    released(hrp2_console)
    playwright_api.expect(page.locator("#banner")).to_be_hidden()
    page.get_by_role("button", name="E-STOP", exact=True).click()
    wait_until(lambda: hrp2_console.state()["emergency"]["hard_stop"], 5.0, "hard_stop == true in /api/state")
    # the page sent it on the e-stop's own door into the robot process too, which answered (the page also
    # POSTs it and sends it on its stick stream: whichever answers first counts)
    door = wait_until(lambda: page.evaluate("(() => { const r = window.hrp2Estops[window.hrp2Estops.length - 1]; "
                                            "return r && r.door_reply; })()"), 5.0, "the door's answer")
    # whichever copy reached the loop first engaged it: the door's answer says which
    assert door["ok"] and door["via"] == "door" and door["engaged"] and door["message"] in (
        "hard e-stop engaged", "hard e-stop already engaged",
        "hard e-stop engaged (by another copy of this press)"), door
    playwright_api.expect(page.locator("#banner")).to_be_visible()
    playwright_api.expect(page.locator("#banner")).to_contain_text("HARD E-STOP ENGAGED")
    playwright_api.expect(page.locator("#stop-hard")).to_have_class(re.compile(r"\bon\b"))
    shot(page, artifacts, "estop_engaged")
    page.get_by_role("button", name="Release e-stop").click()
    try:
        wait_until(lambda: not hrp2_console.state()["emergency"]["hard_stop"], 5.0, "hard_stop == false")
    except AssertionError:
        raise AssertionError("the release did not reach the loop; the page says: "
                             + page.locator("#history").inner_text()[-600:]) from None
    playwright_api.expect(page.locator("#banner")).to_be_hidden()
    # the press went three ways with one id: its other copies (answered or still on their way) engage nothing
    # after the release (before the ids, one arriving late re-engaged the stop)
    time.sleep(0.5)
    assert not hrp2_console.state()["emergency"]["hard_stop"], "a copy of the press engaged the stop again"
    rec = page.evaluate("window.hrp2Estops[window.hrp2Estops.length - 1]")
    assert re.fullmatch(r"page-\w+:\d+", rec["press"]), rec


def joint_deg(c: Console, name: str) -> float:
    return c.state()["joints"][name]["meas_deg"]


def from_half_sitting(c: Console) -> None:
    """The simulation reset to half-sitting on its scene and the balance layers blended in: a test whose outcome
    depends on the stance (which limit a stretched arm meets first) does not inherit the steps and pushes of the
    tests before it."""
    post_json(f"{c.base}/api/sim/reset", {"scene": c.state()["scene"]}, timeout=60.0)
    wait_until(lambda: (s := c.state())["layers"]["abc"]["weight"] == 1.0 and s["layers"]["st"]["weight"] == 1.0,
               30.0, "the AutoBalancer and the Stabilizer blended in")


def motion_released(c: Console) -> None:
    """No motion stop (released through the API if a test left one) and its blend back over."""
    if c.state()["emergency"]["motion_stop"]:
        post_json(f"{c.base}/api/motion/release")
    wait_until(lambda: not c.state()["emergency"]["motion_stop"], 5.0, "motion_stop == false")
    wait_until(lambda: not c.state()["layers"]["es"]["recovering"], 10.0, "es recovering == false")


def test_stop_motion_holds_a_joint_motion_and_release_motion_lets_it_finish(page, hrp2_console, artifacts):
    """A 30 deg joint motion over 8 s (long enough that a click delayed by a busy software-GL browser still
    lands in it); Stop motion: Eq. 15 reverts the plan T1 back and holds it there, short of the target;
    Release motion blends back to the live plan, which reaches the target."""
    released(hrp2_console)
    motion_released(hrp2_console)
    joint = "RARM_JOINT0"
    start = joint_deg(hrp2_console, joint)
    target = start - 30.0
    post_json(f"{hrp2_console.base}/api/sequence/joint-angles", {"angles_deg": {joint: target}, "time": 8.0})
    wait_until(lambda: joint_deg(hrp2_console, joint) < start - 3.0, 10.0, f"{joint} on its way")
    page.get_by_role("button", name="Stop motion", exact=True).click()
    em = wait_until(lambda: (e := hrp2_console.state()["emergency"])["motion_stop"] and e, 5.0, "motion_stop")
    at_stop = joint_deg(hrp2_console, joint)
    assert at_stop > target + 3.0, f"the stop came after the motion had ended ({at_stop:.1f} deg)"
    assert em["motion_stop_reason"] == "operator" and not em["hard_stop"]
    playwright_api.expect(page.locator("#s-motion")).to_have_text("STOPPED (operator)")
    playwright_api.expect(page.locator("#stop-motion")).to_have_class(re.compile(r"\bon\b"))
    playwright_api.expect(page.locator("#latched")).to_be_hidden()  # the operator's own stop is not an alarm
    es = hrp2_console.state()["layers"]["es"]
    wait_until(lambda: hrp2_console.state()["time"] > em["motion_stop_time"] + es["t2_s"] + 0.2, 5.0,
               "the revert over (T2)")
    held = joint_deg(hrp2_console, joint)
    time.sleep(1.0)
    assert joint_deg(hrp2_console, joint) == pytest.approx(held, abs=0.5), "the joint did not hold"
    # reverted (back toward the start, 0.5 deg of tracking allowed), not gone on to the target
    assert held >= at_stop - 0.5 and held > target + 3.0, (start, at_stop, held)
    shot(page, artifacts, "motion_stopped")
    page.get_by_role("button", name="Release motion", exact=True).click()
    wait_until(lambda: not hrp2_console.state()["emergency"]["motion_stop"], 5.0, "motion_stop released")
    playwright_api.expect(page.locator("#s-motion")).to_have_text("off")
    # blended back to the live plan: the joint reaches the target the sequence was going to
    wait_until(lambda: abs(joint_deg(hrp2_console, joint) - target) < 1.0, 20.0, f"{joint} at its target")
    post_json(f"{hrp2_console.base}/api/sequence/joint-angles", {"angles_deg": {joint: start}, "time": 1.5})
    wait_until(lambda: abs(joint_deg(hrp2_console, joint) - start) < 1.0, 10.0, f"{joint} back")


def test_stop_walking_ends_a_walk_in_place(page, hrp2_console, artifacts):
    released(hrp2_console)
    motion_released(hrp2_console)
    post_json(f"{hrp2_console.base}/api/walk/go-velocity", {"vx": 0.1, "vy": 0.0, "vtheta_deg": 0.0})
    wait_until(lambda: hrp2_console.state()["walking"], 10.0, "walking")
    time.sleep(2.0)  # well into the walk
    page.get_by_role("button", name="Stop walking", exact=True).click()
    try:
        stopping = wait_until(lambda: (s := hrp2_console.state())["emergency"]["walking_stop"] and s, 5.0,
                              "walking_stop in /api/state")
    except AssertionError as exc:  # (failed once in CI: what did the page say about the click?)
        raise AssertionError(f"{exc}; the page's history ends: {page.locator('#history').inner_text()[-600:]!r}; "
                             f"walking: {hrp2_console.state()['walking']}") from None
    x0 = stopping["base"]["pos"][0]
    playwright_api.expect(page.locator("#s-walkstop")).to_have_text("STOPPING in place")
    playwright_api.expect(page.locator("#stop-walking")).to_have_class(re.compile(r"\bon\b"))
    shot(page, artifacts, "walking_stop")
    s = wait_until(lambda: (s := hrp2_console.state()) and not s["walking"] and s, 15.0, "standing again")
    # in place: the foot in the air lands, no further step (bound: the measured travel + 0.04 m)
    assert s["base"]["pos"][0] - x0 < WALK_STOP_TRAVEL_M, s["base"]["pos"][0] - x0
    wait_until(lambda: not hrp2_console.state()["emergency"]["walking_stop"], 5.0, "the walking stop ends itself")
    playwright_api.expect(page.locator("#s-walkstop")).to_have_text("off")
    assert not s["fallen"]


def test_stop_and_release_the_stabilizer_from_their_buttons(page, hrp2_console, artifacts):
    released(hrp2_console)
    page.get_by_role("button", name="Stop stabilizer", exact=True).click()
    s = wait_until(lambda: (s := hrp2_console.state())["emergency"]["stabilizer_stop"] and s, 5.0, "stabilizer_stop")
    assert not s["layers"]["st"]["active"]
    playwright_api.expect(page.locator("#s-ststop")).to_have_text("STOPPED")
    playwright_api.expect(page.locator("#stop-stabilizer")).to_have_class(re.compile(r"\bon\b"))
    shot(page, artifacts, "stabilizer_stopped")
    page.get_by_role("button", name="Release stabilizer", exact=True).click()
    s = wait_until(lambda: (s := hrp2_console.state()) and not s["emergency"]["stabilizer_stop"] and s, 5.0,
                   "the Stabilizer running again")
    assert s["layers"]["st"]["active"] and not s["fallen"]
    playwright_api.expect(page.locator("#s-ststop")).to_have_text("running")
    wait_until(lambda: hrp2_console.state()["layers"]["st"]["weight"] == 1.0, 10.0, "blended in again")


def s_threshold(hrp2_console) -> float:
    return hrp2_console.state()["capture_point"]["cp_threshold_m"]


def test_a_push_that_raises_the_cp_flag_latches_a_motion_stop_shown_as_an_alert(page, hrp2_console, artifacts):
    released(hrp2_console)
    motion_released(hrp2_console)
    wait_until(lambda: hrp2_console.state()["layers"]["st"]["weight"] == 1.0, 10.0, "the Stabilizer fully on")
    post_json(f"{hrp2_console.base}/api/sim/push", {"body": "BODY", "force": [200.0, 0.0, 0.0], "duration": 0.1})
    em = wait_until(lambda: (e := hrp2_console.state()["emergency"])["motion_stop"] and e, 5.0,
                    "a motion stop from the CP flag")
    assert em["motion_stop_reason"] == "capture_point" and em["flag_rose_at"] is not None
    alert = page.get_by_role("alertdialog")
    playwright_api.expect(alert).to_be_visible()
    playwright_api.expect(alert).to_contain_text("motion stop latched by capture_point")
    # the CP error that raised the flag and when, not the value at the time of reading (issue 27)
    assert em["motion_stop_cp_error_m"] > s_threshold(hrp2_console)
    playwright_api.expect(alert).to_contain_text(
        f"at {em['motion_stop_time']:.3f} s (CP error {1000 * em['motion_stop_cp_error_m']:.1f} mm when the flag rose)")
    shot(page, artifacts, "latched_alert")
    alert.get_by_role("button", name="Acknowledge").click()
    playwright_api.expect(alert).to_be_hidden()
    s = hrp2_console.state()
    assert s["emergency"]["motion_stop"] and not s["fallen"]  # acknowledged, still latched
    playwright_api.expect(page.locator("#s-motion")).to_have_text("STOPPED (capture_point)")
    # a release is refused while the flag is still up (it would latch again on the next tick), taken once it drops
    wait_until(lambda: not hrp2_console.state()["emergency"]["flag"], 10.0, "the CP flag down")
    page.get_by_role("button", name="Release motion", exact=True).click()
    wait_until(lambda: not hrp2_console.state()["emergency"]["motion_stop"], 5.0, "released")
    playwright_api.expect(page.locator("#s-motion")).to_have_text("off")
    motion_released(hrp2_console)


@pytest.mark.parametrize("kind, fault", [("layer", "RuntimeError: injected fault in layer 'st'"),
                                         ("nan", "PhysicsDiverged: the simulation diverged")])
def test_a_fault_is_shown_on_the_page_and_its_reset_control_recovers(page, hrp2_console, artifacts, kind, fault):
    released(hrp2_console)
    post_json(f"{hrp2_console.base}/api/sim/fault", {"kind": kind, "layer": "st"})
    em = wait_until(lambda: (e := hrp2_console.state()["emergency"])["fault"] and e, 5.0, "the fault in /api/state")
    assert em["hard_stop"] and em["hard_stop_reason"] == "fault" and em["fault"].startswith(fault)
    playwright_api.expect(page.locator("#banner")).to_contain_text(f"fault: {fault}")
    playwright_api.expect(page.locator("#s-fault")).to_contain_text(fault)
    playwright_api.expect(page.get_by_role("alertdialog")).to_contain_text(f"fault: {fault}")
    playwright_api.expect(page.locator("#history")).to_contain_text(f"FAULT: {fault}")
    shot(page, artifacts, f"fault_{kind}")
    page.get_by_role("alertdialog").get_by_role("button", name="Acknowledge").click()
    page.locator("#scene").select_option(hrp2_console.state()["scene"])
    page.get_by_role("button", name="Reset simulation").click()
    s = wait_until(lambda: (s := hrp2_console.state()) and not s["emergency"]["hard_stop"] and s, 30.0,
                   "the hard stop gone after the reset")
    assert s["emergency"]["fault"] is None and not s["fallen"]
    playwright_api.expect(page.locator("#banner")).to_be_hidden()
    playwright_api.expect(page.locator("#s-fault")).to_have_text("none")
    playwright_api.expect(page.locator("#s-hard")).to_have_text("off")
    playwright_api.expect(page.locator("#conn")).to_contain_text("live")
    t = hrp2_console.state()["time"]
    wait_until(lambda: hrp2_console.state()["time"] > t + 0.5, 5.0, "the simulation running on")
    shot(page, artifacts, f"fault_{kind}_recovered")


@pytest.mark.parametrize("key, where", [("Space", "page"), ("Escape", "page"), ("Escape", "3D view"),
                                        ("Space", "3D view")])
def test_space_and_esc_engage_the_hard_stop_from_anywhere(page, hrp2_console, artifacts, key, where):
    released(hrp2_console)
    if where == "3D view":
        frame = page.frame_locator("#view iframe")
        frame.locator("canvas[data-engine]").first.click(position={"x": 40, "y": 300})
        focused = page.evaluate("document.activeElement && document.activeElement.tagName")
        assert focused == "IFRAME", f"the focus is on {focused}, not in the 3D view"
        frame.locator("body").press(key)
    else:
        page.locator("#s-chain").click()  # somewhere on the page that is not a field
        page.keyboard.press(key)
    wait_until(lambda: hrp2_console.state()["emergency"]["hard_stop"], 5.0, f"{key} in the {where}: hard_stop")
    shot(page, artifacts, f"key_{key}_{where.replace(' ', '_')}")
    released(hrp2_console)


def test_keys_typed_in_the_command_box_do_not_engage_the_estop(page, hrp2_console, artifacts):
    released(hrp2_console)
    box = page.get_by_role("textbox", name="command")
    box.fill("")
    box.press_sequentially("a b")
    box.press("Escape")
    time.sleep(0.3)
    assert not hrp2_console.state()["emergency"]["hard_stop"]
    assert box.input_value() == "a b"
    shot(page, artifacts, "keys_in_command_box")
    box.fill("")


@pytest.mark.usefixtures("deadman_lengthened")
def test_an_on_screen_stick_drives_the_walk_and_releasing_it_zeroes_the_velocity(page, hrp2_console, artifacts):
    released(hrp2_console)
    page.get_by_role("radio", name="walk").click()
    playwright_api.expect(page.locator("#sel-point")).to_have_text("walk")
    page.locator("#stick-left").scroll_into_view_if_needed()
    pad = page.locator("#stick-left .pad").bounding_box()
    cx, cy = pad["x"] + pad["width"] / 2, pad["y"] + pad["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx, cy - 0.4 * pad["height"], steps=4)  # forward, 80 % of the way to the rim
    try:
        wait_until(lambda: motion(hrp2_console, "walk")[0] > 0.05, 10.0, "vx > 0.05 m/s at the walking point")
        wait_until(lambda: hrp2_console.state()["walking"], 10.0, "walking")
        vx = motion(hrp2_console, "walk")[0]
        assert 0.05 < vx <= 0.2 + 1e-9  # (full deflection is 0.2 m/s)
        playwright_api.expect(page.locator("#stream-state")).to_contain_text("streaming walk")
        shot(page, artifacts, "stick_walk")
        t_before = let_go_timer(hrp2_console, page)
    finally:
        page.mouse.up()
    dt = zeroed_within(hrp2_console, page, "walk", t_before)
    assert dt <= ZERO_WITHIN_S, f"the walk velocity went to zero {dt * 1e3:.0f} ms after the release"
    playwright_api.expect(page.locator("#latency")).to_contain_text("ms")
    post_json(f"{hrp2_console.base}/api/walk/stop")
    wait_until(lambda: not hrp2_console.state()["walking"], 20.0, "standing again")


def target(c: Console, point: str) -> list[float]:
    return c.state()["operation"]["points"][point]["target"]


def settled_target_x(c: Console, point: str, timeout: float = 5.0) -> float:
    """The point's target x once it is no longer limited and unchanged over three reads 0.15 s apart (0.3 s): a
    hand released at its reach limit follows the IK's best effort back a few mm first (measured 6-7 mm in up to
    ~0.6 s), then holds exactly."""
    reads: list[float | None] = []

    def still():
        p = c.state()["operation"]["points"][point]
        reads.append(p["target"][0] if p["limited"] is None else None)
        last = reads[-3:]
        return len(last) == 3 and None not in last and max(last) - min(last) < 1e-4 and last[-1]

    return wait_until(still, timeout, f"the {point} target not limited and still for 0.3 s", period=0.15)


@pytest.mark.usefixtures("deadman_lengthened")
def test_held_keys_drive_the_selected_point_and_letting_go_stops_it(page, hrp2_console, artifacts):
    released(hrp2_console)
    motion_released(hrp2_console)
    page.locator("#s-chain").click()  # the focus on the page, not in a field
    page.keyboard.press("Digit1")  # key 1: the first point, rhand
    playwright_api.expect(page.locator("#sel-point")).to_have_text("rhand")
    page.keyboard.down("KeyW")  # W: forward, half deflection (KEY_DEFLECTION 0.5 of 0.1 m/s)
    try:
        # (the twist ramps up under the hands' 0.5 m/s^2 acceleration limit)
        wait_until(lambda: motion(hrp2_console, "rhand") == pytest.approx([0.05, 0, 0, 0, 0, 0], abs=1e-6), 10.0,
                   "the right hand moving forward at 0.05 m/s")
        playwright_api.expect(page.locator("#stream-state")).to_contain_text("streaming rhand")
        x0 = target(hrp2_console, "rhand")[0]
        wait_until(lambda: target(hrp2_console, "rhand")[0] > x0 + 0.02, 5.0, "the hand's target 2 cm forward")
        shot(page, artifacts, "keys_drive_rhand")
        t_before = let_go_timer(hrp2_console, page)
    finally:
        page.keyboard.up("KeyW")
    dt = zeroed_within(hrp2_console, page, "rhand", t_before)
    assert dt <= ZERO_WITHIN_S, f"the hand velocity went to zero {dt * 1e3:.0f} ms after the key was let go"
    x_zero = target(hrp2_console, "rhand")[0]
    # the hands' 0.5 m/s^2 limit brings 0.05 m/s to rest in 0.1 s (2.5 mm); near the reach limit the target
    # settles back a few mm (see the touch test); going on would be 25 mm in 0.5 s
    x1 = settled_target_x(hrp2_console, "rhand")
    assert x1 <= x_zero + 3e-3, "the hand moved on after the keys"
    time.sleep(0.5)
    assert target(hrp2_console, "rhand")[0] == pytest.approx(x1, abs=5e-4), "the hand moved after it had settled"
    playwright_api.expect(page.locator("#stream-state")).to_have_text("idle")


def test_a_touch_on_a_stick_drives_a_hand_to_its_reach_limit_and_the_readouts_say_so(page, hrp2_console, artifacts):
    """A real touch (Chromium's touch emulation: pointer events of pointerType "touch") on the left stick at
    full forward deflection drives the right hand (0.1 m/s) until the IK limits it ("reach", measured after
    3.4 s of control time from half-sitting); the "limited" readout says so, the round trip shows a number.
    The touch ended, the hand stops (within ZERO_WITHIN_S is the mouse test's: the same handlers; Chromium's
    emulated touch under software GL on a loaded 2-CPU machine was measured to take up to 0.38 s).
    From half-sitting: after the earlier tests' walks and pushes left the feet turned, a CI run met the elbow's
    joint limit first ("joint_limit", as true there)."""
    released(hrp2_console)
    from_half_sitting(hrp2_console)
    motion_released(hrp2_console)
    page.get_by_role("radio", name="rhand").click()
    playwright_api.expect(page.locator("#sel-point")).to_have_text("rhand")
    page.locator("#stick-left").scroll_into_view_if_needed()
    page.evaluate("""() => { window.__pointerTypes = [];
        document.querySelector('#stick-left .pad').addEventListener(
            'pointerdown', (e) => window.__pointerTypes.push(e.pointerType)); }""")
    pad = page.locator("#stick-left .pad").bounding_box()
    cx, cy = pad["x"] + pad["width"] / 2, pad["y"] + pad["height"] / 2
    cdp = page.context.new_cdp_session(page)
    cdp.send("Emulation.setTouchEmulationEnabled", {"enabled": True, "maxTouchPoints": 1})
    touching = False
    try:
        cdp.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [{"x": cx, "y": cy}]})
        touching = True
        for k in range(1, 5):  # to the rim, straight up: full forward
            cdp.send("Input.dispatchTouchEvent", {"type": "touchMove",
                                                  "touchPoints": [{"x": cx, "y": cy - k * 0.15 * pad["height"]}]})
        assert page.evaluate("window.__pointerTypes") == ["touch"]
        wait_until(lambda: motion(hrp2_console, "rhand")[0] == pytest.approx(0.1, abs=1e-6), 10.0,
                   "the right hand moving forward at full deflection, 0.1 m/s")
        op = wait_until(lambda: (p := hrp2_console.state()["operation"]["points"]["rhand"])["limited"] and p,
                        20.0, "the right hand limited")
        assert op["limited"] == "reach"
        playwright_api.expect(page.locator("#limited")).to_have_text("reach")
        playwright_api.expect(page.locator("#limited")).to_have_class("alarm")
        shot(page, artifacts, "touch_stick_reach_limit")
        t_before = let_go_timer(hrp2_console, page)
    finally:
        if touching:
            cdp.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
        cdp.send("Emulation.setTouchEmulationEnabled", {"enabled": False})
        cdp.detach()
    zeroed_within(hrp2_console, page, "rhand", t_before)  # (how soon: the mouse test's bound, same handler)
    x0 = target(hrp2_console, "rhand")[0]
    # at the reach limit the target is the achieved pose: while the IK still finds it out of reach (limited
    # "reach", for up to ~0.4 s) it follows the IK's best effort back, 6-7 mm in all (measured, read every 0.05 s),
    # then holds exactly, no longer limited. The operator's twist read zero, the hand's own rate still ramps down
    # under the 0.5 m/s^2 limit: 0.1 m/s comes to rest in 0.2 s, 10 mm, which the target makes whenever the IK
    # finds the hand back in reach meanwhile (one CI run under load: 3.9 mm forward). Going on at 0.1 m/s would be
    # 50 mm in 0.5 s
    x1 = settled_target_x(hrp2_console, "rhand")
    assert x1 <= x0 + 0.1 ** 2 / (2 * 0.5) + 1e-3, "the hand moved on after the touch"
    time.sleep(0.5)
    assert target(hrp2_console, "rhand")[0] == pytest.approx(x1, abs=5e-4), "the hand moved after it had settled"
    playwright_api.expect(page.locator("#limited")).to_have_text("no")
    latency = re.fullmatch(r"(\d+\.\d) ms \(median of (\d+)\)", page.locator("#latency").inner_text())
    assert latency and 0.0 < float(latency.group(1)) < 1000.0 and int(latency.group(2)) >= 1, latency
    run = post_json(f"{hrp2_console.base}/api/behaviors/stand", {})  # the hand back
    # (the state is published every 50 ms: the run may not be in it yet)
    wait_until(lambda: next((r for r in hrp2_console.state()["runs"] if r["id"] == run["id"]),
                            {"state": "running"})["state"] != "running",
               20.0, "stand to end")


@pytest.mark.usefixtures("deadman_lengthened")
def test_an_injected_gamepad_drives_a_hand_and_letting_go_of_the_deadman_stops_it(page, hrp2_console, artifacts):
    released(hrp2_console)
    page.evaluate("""() => {
        const button = () => ({pressed: false, touched: false, value: 0});
        window.__pad = {id: "stub gamepad", index: 0, connected: true, mapping: "standard", timestamp: 0,
                        axes: [0, 0, 0, 0], buttons: Array.from({length: 17}, button)};
        Object.defineProperty(navigator, "getGamepads", {configurable: true, value: () => [window.__pad, null]});
    }""")
    page.get_by_role("radio", name="rhand").click()
    playwright_api.expect(page.locator("#gamepad")).to_contain_text("stub gamepad")
    # the stick forward without the dead-man: nothing moves
    page.evaluate("() => { window.__pad.axes[1] = -0.6; }")
    time.sleep(0.3)
    assert motion(hrp2_console, "rhand") == [0.0] * 6
    page.evaluate("() => { window.__pad.buttons[5] = {pressed: true, touched: true, value: 1}; }")
    try:
        wait_until(lambda: motion(hrp2_console, "rhand")[0] > 0.02, 10.0, "the right hand moving forward")
        s = hrp2_console.state()
        assert s["operation"]["points"]["rhand"]["target"] is not None
        expected = 0.1 * (0.6 - 0.1) / 0.9  # [m/s] full deflection 0.1, past the 0.1 dead zone
        assert s["operation"]["points"]["rhand"]["motion"][0] == pytest.approx(expected, abs=0.01)
        playwright_api.expect(page.locator("#gamepad")).to_contain_text("dead-man HELD")
        shot(page, artifacts, "gamepad_hand")
        t_before = let_go_timer(hrp2_console, page)
    finally:
        page.evaluate("() => { window.__pad.buttons[5] = {pressed: false, touched: false, value: 0}; }")
    playwright_api.expect(page.locator("#gamepad")).to_contain_text("dead-man released")
    # (from before the pad's change: the page reads the pad at 50 Hz and every animation frame)
    dt = zeroed_within(hrp2_console, page, "rhand", t_before)
    assert dt <= ZERO_WITHIN_S, f"the hand velocity went to zero {dt * 1e3:.0f} ms after the dead-man was let go"
    # the stream stops: the page has gone quiet (idle) and the hand holds still
    playwright_api.expect(page.locator("#stream-state")).to_have_text("idle")
    # the gamepad's B button is an e-stop too
    page.evaluate("() => { window.__pad.axes[1] = 0; "
                  "window.__pad.buttons[1] = {pressed: true, touched: true, value: 1}; }")
    wait_until(lambda: hrp2_console.state()["emergency"]["hard_stop"], 5.0, "gamepad B: hard_stop")
    page.evaluate("() => { window.__pad.buttons[1] = {pressed: false, touched: false, value: 0}; }")
    released(hrp2_console)


def test_a_behaviour_button_starts_a_run_and_its_progress_appears(page, hrp2_console, artifacts):
    released(hrp2_console)
    page.locator("#behaviors").get_by_role("button", name="squat", exact=True).click()
    form = page.locator("#behavior-form")
    playwright_api.expect(form).to_be_visible()
    playwright_api.expect(form).to_contain_text("[m]")  # units and ranges beside the fields
    form.get_by_label("depth_m").fill("0.05")
    form.get_by_role("button", name="Start squat").click()
    run = page.locator("#runs .run", has_text="squat").last
    playwright_api.expect(run).to_contain_text(re.compile(r"running \(\d+ %\)"))
    runs = wait_until(lambda: [r for r in hrp2_console.state()["runs"] if r["behavior"] == "squat"], 5.0, "a squat run")
    assert runs[-1]["params"]["depth_m"] == pytest.approx(0.05)
    shot(page, artifacts, "behaviour_running")
    playwright_api.expect(page.locator("#history")).to_contain_text("squat succeeded", timeout=30_000)


def test_the_command_box_runs_walk_to_and_the_history_shows_the_result(page, hrp2_console, artifacts):
    released(hrp2_console)
    box = page.get_by_role("textbox", name="command")
    box.fill("squat 9")
    box.press("Enter")
    playwright_api.expect(page.locator("#history")).to_contain_text("depth_m: 9 is outside [m] -0.05 .. 0.25")
    box.fill("walk_to 0.1 0 0")
    box.press("Enter")
    playwright_api.expect(page.locator("#history")).to_contain_text("walk_to started")
    run = [r for r in hrp2_console.state()["runs"] if r["behavior"] == "walk_to"][-1]
    assert run["params"]["x_m"] == pytest.approx(0.1) and run["params"]["y_m"] == 0.0
    playwright_api.expect(page.locator("#history")).to_contain_text(
        re.compile(rf"walk_to succeeded in [\d.]+ s: .*\(run {run['id']}\)"), timeout=40_000)
    shot(page, artifacts, "command_walk_to")


def test_a_command_a_script_sends_appears_in_the_pages_history(page, hrp2_console, artifacts):
    released(hrp2_console)
    motion_released(hrp2_console)
    joint = "LARM_JOINT0"
    angle = round(joint_deg(hrp2_console, joint) - 10.0, 1)
    body = {"angles_deg": {joint: angle}, "time": 1.0}
    answer = post_json(f"{hrp2_console.base}/api/sequence/joint-angles", body, client="script-7")
    entry = hrp2_console.state()["commands"][-1]
    assert entry["client"] == "script-7" and entry["request"] == "POST /api/sequence/joint-angles"
    line = page.locator('#history li[data-who="script-7"]').filter(has_text=answer["message"])  # its words
    playwright_api.expect(line).to_have_count(1)
    line.locator("summary").click()  # and what it sent, behind a click
    playwright_api.expect(line.locator("pre.raw")).to_contain_text('"request": "POST /api/sequence/joint-angles"')
    playwright_api.expect(line.locator("pre.raw")).to_contain_text(json.dumps(json.dumps(body, separators=(",", ":"))))
    wait_until(lambda: abs(joint_deg(hrp2_console, joint) - angle) < 1.0, 10.0, f"{joint} moved by the script")
    line.scroll_into_view_if_needed()
    shot(page, artifacts, "history_other_client")
    post_json(f"{hrp2_console.base}/api/sequence/joint-angles", {"angles_deg": {joint: angle + 10.0}, "time": 1.0})


def test_the_camera_view_updates(page, artifacts):
    shown = "() => ({...window.hrp2Camera})"  # the frame on screen: its seq and blob URL, read together
    first = wait_until(lambda: (c := page.evaluate(shown))["frames"] >= 1 and c, 30.0, "a first camera frame")
    t0 = time.monotonic()
    later = wait_until(lambda: (c := page.evaluate(shown))["seq"] > first["seq"] and c, 10.0,
                       "a second, different frame")
    assert later["src"] != first["src"]
    # (the page's own record of the frame on screen: the image's src read beside it may already be the next frame,
    # still loading, which then, shown, was "a second frame" with the same URL: two CI runs failed so)
    # how soon is a speed goal, the page-rates benchmark's (camera >= 10 Hz shown), not this test's
    print(f"a second camera frame shown {time.monotonic() - t0:.2f} s after the first")
    # the size of a decoded image (read while the next frame loads, a blank one may be read: wait for one)
    decoded = ("(() => { const i = document.getElementById('camera-img'); "
               "return i.complete ? [i.naturalWidth, i.naturalHeight] : null; })()")
    size = wait_until(lambda: page.evaluate(decoded), 10.0, "a decoded camera image")
    assert size == [320, 240] and later["meta"]["camera"] == "wide"
    playwright_api.expect(page.locator("#camera-info")).to_contain_text("Hz")
    estop = page.get_by_role("button", name="E-STOP", exact=True).bounding_box()
    assert estop["height"] >= 0.10 * 800  # still, with the camera on the page
    shot(page, artifacts, "camera_view")


def test_the_plots_data_grows(page, artifacts):
    spans = "Object.values(hrp2Plots).map((p) => p.t.length ? p.t[p.t.length - 1] - p.t[0] : 0)"  # [s] shown
    span0 = page.evaluate(spans)
    t0 = page.evaluate("hrp2Plots.f.t[hrp2Plots.f.t.length - 1] || 0")
    page.locator("#plots").scroll_into_view_if_needed()
    draws = page.evaluate("hrp2Plots.f.draws")
    legend = page.locator("#legend-f").inner_text()
    wait_until(lambda: page.evaluate("hrp2Plots.f.t[hrp2Plots.f.t.length - 1]") > t0 + 1.0, 20.0,
               "the plots' newest sample 1 s later")
    span1 = page.evaluate(spans)  # each plot shows more time, or its whole 10 s window
    assert all(b > a or b >= 9.0 for a, b in zip(span0, span1, strict=True)), (span0, span1)
    forces = page.evaluate("hrp2Plots.f.v.map((a) => a[a.length - 1])")
    assert 150 < sum(forces) / 2 < 450, f"foot forces {forces} N: standing, each foot carries about half"
    # redrawn (a standing robot's flat lines may look the same from one frame to the next: the count says)
    assert page.evaluate("hrp2Plots.f.draws") > draws and page.locator("#legend-f").inner_text() != legend
    playwright_api.expect(page.locator("#legend-x")).to_contain_text("ZMP x")
    shot(page, artifacts, "plots")


RATE_WINDOW_S = 3.0  # [s] of wall time over which the camera's and the plots' updates are counted


def test_the_camera_and_every_plot_keep_updating_while_watched(page, hrp2_console, artifacts):
    """Over RATE_WINDOW_S at once, each stream delivers to a script beside the page and each view of the page
    shows new frames, samples and redraws, the CP-error panel's too. How fast is the `page-rates` benchmark's
    (`hrp2-console bench --scenario page-rates`, docs/measurements/speed.md): the issue's camera >= 10 Hz and
    plots >= 20 Hz are speed goals, not this test's (the CP panel's >= 10 Hz is test_page_layout.py's)."""
    from app.lab.bench_browser import measure_page_rates

    page.locator("#camera").scroll_into_view_if_needed()
    rates = measure_page_rates(page, hrp2_console.base, RATE_WINDOW_S)
    print(rates)
    for group in ("delivered_hz", "shown_hz"):
        for name, hz in rates[group].items():
            assert hz > 0.0, f"{group}[{name}] did not update in {RATE_WINDOW_S} s: {rates}"
    shot(page, artifacts, "rates")


def test_take_and_release_control_with_two_pages(page, hrp2_console, artifacts):
    released(hrp2_console)
    watcher = page.context.browser.new_page(viewport={"width": 1280, "height": 800})  # its own context: a client
    try:
        watcher.set_default_timeout(40_000)
        watcher.goto(f"{hrp2_console.base}/", wait_until="domcontentloaded")
        playwright_api.expect(watcher.locator("#conn")).to_contain_text("live", timeout=30_000)
        playwright_api.expect(watcher.locator("#lock-state")).to_contain_text("free")
        page.get_by_role("button", name="Take control").click()
        playwright_api.expect(page.locator("#lock-state")).to_have_text("control: YOU")
        holder = hrp2_console.state()["operator_lock"]["holder"]
        assert holder and holder.startswith("page-")
        playwright_api.expect(watcher.locator("#lock-state")).to_contain_text(f"{holder} (watching)")
        assert "watching" in watcher.evaluate("document.body.className")
        assert watcher.evaluate("document.querySelector('#controls > section').inert")
        assert watcher.locator("#st-stop").is_disabled()
        shot(watcher, artifacts, "watcher_greyed")
        # the watcher's E-STOP still works (any authenticated client, always)
        watcher.get_by_role("button", name="E-STOP", exact=True).click()
        wait_until(lambda: hrp2_console.state()["emergency"]["hard_stop"], 5.0, "the watcher's E-STOP")
        # the watcher cannot release it, not even under the holder's name (a display name proves nothing), nor
        # take the lock away; the operator can
        for name in ("page-other", holder):
            r = watcher.evaluate("""async (name) => (await fetch('/api/estop/release', {method: 'POST',
                headers: {'Content-Type': 'application/json', 'X-Client-Id': name}})).status""", name)
            assert r == 423, name
        r = watcher.evaluate("""async (name) => (await fetch('/api/operator/lock', {method: 'DELETE',
            headers: {'Content-Type': 'application/json', 'X-Client-Id': name}})).status""", holder)
        assert r == 423
        assert hrp2_console.state()["operator_lock"]["holder"] == holder
        page.get_by_role("button", name="Release e-stop").click()
        wait_until(lambda: not hrp2_console.state()["emergency"]["hard_stop"], 5.0, "released by the operator")
        # the holder's streams reconnected with its lease: they keep the lock, and its stick steers
        wait_until(lambda: hrp2_console.state()["operator_lock"]["connected"], 5.0, "the holder's streams")
        page.locator("#s-chain").click()
        page.keyboard.press("Digit1")  # rhand
        page.keyboard.down("KeyW")
        try:
            wait_until(lambda: motion(hrp2_console, "rhand")[0] > 0.01, 10.0, "the holder's stick moving the hand")
        finally:
            page.keyboard.up("KeyW")
        page.get_by_role("button", name="Release control").click()
        playwright_api.expect(watcher.locator("#lock-state")).to_contain_text("free")
        assert "watching" not in watcher.evaluate("document.body.className")
        assert not watcher.evaluate("document.querySelector('#controls > section').inert")
    finally:
        watcher.close()
    released(hrp2_console)


def put_json(url: str, body: dict, timeout: float = 5.0) -> dict:
    req = urllib.request.Request(url, data=json.dumps(body).encode(), method="PUT",
                                 headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=timeout) as r:
        return json.loads(r.read())


@pytest.mark.parametrize("label, layer", [("auto-balancer", "abc"), ("impedance rarm", "ic.rarm")])
def test_start_and_stop_buttons_from_the_openapi_drive_the_layer(page, hrp2_console, artifacts, label, layer):
    released(hrp2_console)
    if layer == "abc":  # it stops only where its reference places BODY (not after the walks of earlier tests)
        from_half_sitting(hrp2_console)

    def status() -> dict:
        d = hrp2_console.state()["layers"]
        for part in layer.split("."):
            d = d[part]
        return d

    was_active = status()["active"]
    first, then = ("stop", "start") if was_active else ("start", "stop")
    box = page.locator("#layer-buttons")
    box.get_by_role("button", name=f"{first} {label}", exact=True).click()
    wait_until(lambda: status()["active"] is not was_active, 5.0, f"{label} {first}ped in /api/state")
    wait_until(lambda: status()["weight"] == (0.0 if was_active else 1.0), 10.0, f"{label}'s blend over")
    playwright_api.expect(page.locator("#history")).to_contain_text(re.compile(rf"{first}", re.IGNORECASE))
    shot(page, artifacts, f"layer_{label.replace(' ', '_')}_{first}")
    box.get_by_role("button", name=f"{then} {label}", exact=True).click()
    wait_until(lambda: status()["active"] is was_active, 5.0, f"{label} {then}ed again")
    wait_until(lambda: status()["weight"] == (1.0 if was_active else 0.0), 10.0, f"{label}'s blend back")
    assert not hrp2_console.state()["fallen"]


def test_a_parameter_panel_generated_from_a_layer_applies_one_field(page, hrp2_console, artifacts):
    before = get_json(f"{hrp2_console.base}/api/params")["es"]
    panel = page.locator("#params details", has=page.locator("summary", has_text=re.compile(r"^es parameters$")))
    panel.locator("summary").click()
    field = panel.get_by_label("t1_s", exact=True)
    playwright_api.expect(field).to_have_value(str(before["t1_s"]).removesuffix(".0"))
    assert field.get_attribute("min") == "0" and field.get_attribute("max") == "10"  # from the dataclass
    field.fill("0.75")
    panel.get_by_role("button", name="Apply es").click()
    wait_until(lambda: get_json(f"{hrp2_console.base}/api/params")["es"]["t1_s"] == 0.75, 5.0, "es.t1_s 0.75")
    after = get_json(f"{hrp2_console.base}/api/params")["es"]
    assert {k: v for k, v in after.items() if k != "t1_s"} == {k: v for k, v in before.items() if k != "t1_s"}
    playwright_api.expect(page.locator("#history")).to_contain_text('es parameters set: {"t1_s":0.75}')
    shot(page, artifacts, "params_panel")
    field.fill(str(before["t1_s"]))
    panel.get_by_role("button", name="Apply es").click()
    wait_until(lambda: get_json(f"{hrp2_console.base}/api/params")["es"]["t1_s"] == before["t1_s"], 5.0, "back")
    panel.locator("summary").click()


def test_parameters_dump_to_a_json_file_and_load_from_one(page, hrp2_console, artifacts, tmp_path):
    with page.expect_download() as got:
        page.get_by_role("button", name="Dump parameters (JSON)").click()
    download = got.value
    assert download.suggested_filename == "hrp2_params.json"
    dumped = json.loads(Path(download.path()).read_text())
    assert dumped == get_json(f"{hrp2_console.base}/api/params")
    changed = json.loads(json.dumps(dumped))
    changed["es"]["t2_s"] = round(dumped["es"]["t2_s"] + 0.1, 3)
    changed["st"]["cp_threshold_m"] = round(dumped["st"]["cp_threshold_m"] + 0.005, 4)
    path = tmp_path / "tuned.json"
    path.write_text(json.dumps(changed))
    page.locator("#params-load").set_input_files(str(path))
    wait_until(lambda: get_json(f"{hrp2_console.base}/api/params") == changed, 5.0, "the file's parameters loaded")
    playwright_api.expect(page.locator("#history")).to_contain_text("parameters loaded from tuned.json")
    shot(page, artifacts, "params_loaded")
    put_json(f"{hrp2_console.base}/api/params", dumped)
    assert get_json(f"{hrp2_console.base}/api/params") == dumped


def test_reset_to_a_chosen_scene(page, hrp2_console, artifacts):
    released(hrp2_console)
    page.locator("#scene").select_option("expo")
    page.get_by_role("button", name="Reset simulation").click()
    s = wait_until(lambda: (s := hrp2_console.state())["scene"] == "expo" and s, 60.0, "the expo scene")
    assert s["time"] < 30.0 and not s["fallen"]  # a new simulation, from the start
    playwright_api.expect(page.locator("#history")).to_contain_text("scene is now expo")
    assert get_json(f"{hrp2_console.base}/api/sim/objects")["objects"]  # the expo scene's table, can, box
    shot(page, artifacts, "reset_expo")


def in_scene(c: Console, scene: str) -> None:
    """The simulation in `scene` (reset into it when it is in another)."""
    if c.state()["scene"] != scene:
        post_json(f"{c.base}/api/sim/reset", {"scene": scene}, timeout=60.0)
    wait_until(lambda: c.state()["scene"] == scene, 30.0, f"the {scene} scene")


def run_command(page, text: str) -> None:
    box = page.get_by_role("textbox", name="command")
    box.fill(text)
    box.press("Enter")


def last_run(c: Console, behavior: str) -> dict:
    return [r for r in c.state()["runs"] if r["behavior"] == behavior][-1]


def test_the_command_box_looks_at_a_named_place(page, hrp2_console, artifacts):
    released(hrp2_console)
    in_scene(hrp2_console, "expo")
    history = page.locator("#history")
    run_command(page, "look_at sofa")
    playwright_api.expect(history).to_contain_text("unknown place 'sofa'; valid: table, trash_box")
    run_command(page, "look_at table")
    playwright_api.expect(history).to_contain_text("table: table at (2.150, 0.000, 0.750) m (known)")
    playwright_api.expect(history).to_contain_text("look_at started")
    run = last_run(hrp2_console, "look_at")
    assert (run["params"]["x_m"], run["params"]["y_m"], run["params"]["z_m"]) == pytest.approx((2.15, 0.0, 0.75))
    playwright_api.expect(history).to_contain_text(re.compile(rf"look_at succeeded in [\d.]+ s: .*\(run {run['id']}\)"),
                                                   timeout=40_000)
    assert last_run(hrp2_console, "look_at")["result"]["error_deg"] < 1.0  # the gaze on the table's point
    page.locator("#history li").last.scroll_into_view_if_needed()
    shot(page, artifacts, "look_at_table")


def test_a_recognition_popup_appears_after_locate_can_and_confirm_and_correct_reach_the_robot(page, hrp2_console,
                                                                                            artifacts):
    in_scene(hrp2_console, "expo")
    try:
        run = post_json(f"{hrp2_console.base}/api/behaviors/locate_can", {})
        done = wait_until(lambda: next((r for r in hrp2_console.state()["runs"] if r["id"] == run["id"]
                                        and r["state"] != "running"), None), 90.0, "locate_can to end")
        assert done["state"] == "succeeded", done["message"]
        pop = page.locator(".rec-pop", has_text="can at")
        playwright_api.expect(pop).to_be_visible(timeout=15_000)
        playwright_api.expect(pop).to_contain_text("estimated")
        box = page.locator(".rec-box").first
        playwright_api.expect(box).to_be_visible()  # the can is in the view: its box drawn over the image
        shot(page, artifacts, "recognition_popup")
        pop.get_by_role("button", name="Confirm").click()
        wait_until(lambda: get_json(f"{hrp2_console.base}/api/recognitions")["recognitions"]["can"].get("status")
                   == "confirmed", 5.0, "the can confirmed")
        playwright_api.expect(pop).to_contain_text("confirmed")
        # the dialogue asked the same question and says how it was answered (issue 29)
        asked = page.locator('#history li[data-who="robot"]').filter(has_text="I see the can at")
        playwright_api.expect(asked).to_contain_text("can confirmed at (")
        pop.get_by_role("button", name="Correct").click()
        pop.get_by_label("can y [m]").fill("0.05")
        pop.get_by_role("button", name="Send").click()
        rec = wait_until(lambda: (r := get_json(f"{hrp2_console.base}/api/recognitions")["recognitions"]["can"])
                         .get("status") == "corrected" and r, 5.0, "the can corrected")
        assert rec["position_m"][1] == pytest.approx(0.05)
        assert rec["estimated_position_m"][1] != pytest.approx(0.05)
        playwright_api.expect(pop).to_contain_text("corrected")
        shot(page, artifacts, "recognition_corrected")
        # the located can is a place now: look at it (where the operator said it is)
        before = max((r["id"] for r in hrp2_console.state()["runs"]), default=0)
        run_command(page, "look_at can")
        playwright_api.expect(page.locator("#history")).to_contain_text("can: can at (")
        look = wait_until(lambda: next((r for r in hrp2_console.state()["runs"] if r["behavior"] == "look_at"
                                        and r["id"] > before and r["state"] != "running"), None),
                          30.0, "look_at can to end")  # (run alone, no look_at ran before it)
        assert [look["params"][k] for k in ("x_m", "y_m", "z_m")] == pytest.approx(rec["position_m"])
        assert look["state"] == "succeeded", look
    finally:
        post_json(f"{hrp2_console.base}/api/sim/reset", {"scene": "default"}, timeout=60.0)
        wait_until(lambda: hrp2_console.state()["scene"] == "default", 30.0, "back to the default scene")


def test_the_connection_lost_state_appears_when_the_server_stops_and_it_reconnects(page, hrp2_console, artifacts):
    playwright_api.expect(page.locator("#offline")).to_be_hidden()
    port = int(hrp2_console.base.rsplit(":", 1)[1])
    hrp2_console.stop()
    playwright_api.expect(page.locator("#offline")).to_be_visible(timeout=10_000)
    playwright_api.expect(page.locator("#offline")).to_contain_text("Connection lost")
    assert "offline" in page.evaluate("document.body.className")
    shot(page, artifacts, "connection_lost")
    again = start_console(["--port", str(port), "--headless"])
    try:
        playwright_api.expect(page.locator("#offline")).to_be_hidden(timeout=30_000)
        playwright_api.expect(page.locator("#conn")).to_contain_text("live")
    finally:
        again.stop()
