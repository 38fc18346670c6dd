"""A real console in a subprocess (`hrp2-console --headless`, its robot in a process of its own) with a
keep-alive HTTP client, and the load of many clients on it: for the load benchmark and the tests."""

from __future__ import annotations

import http.client
import json
import multiprocessing
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from app.lab.stats import percentiles_ms

ROOT = Path(__file__).resolve().parents[2]
KEPT_LINES = 20000  # of the console's output


class Console:
    """`hrp2-console --headless --port 0 ARGS` until `stop()`; `port` is where its HTTP API listens."""

    def __init__(self, *args: str, timeout_s: float = 90.0, headless: bool = True, viewer_port: int = 0) -> None:
        env = {**os.environ, "PYTHONUNBUFFERED": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
        view = ["--headless"] if headless else ["--viewer-port", str(viewer_port)]
        self.proc = subprocess.Popen([sys.executable, "-m", "app.cli", *view, "--port", "0", *args],
                                     cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.lines: list[str] = []
        deadline = time.monotonic() + timeout_s
        self.port = None
        while self.port is None:
            line = self.proc.stdout.readline()
            if not line:
                raise RuntimeError(f"the console exited before serving:\n{''.join(self.lines)}")
            self.lines.append(line)
            m = re.search(r"operator page\s+http://[^:]+:(\d+)/", line)
            if m:
                self.port = int(m.group(1))
            if time.monotonic() > deadline:
                self.proc.kill()
                raise RuntimeError(f"the console did not start in {timeout_s} s:\n{''.join(self.lines)}")
        # read what it prints from now on, or a full pipe blocks its logging, and its event loop with it
        self._reader = threading.Thread(target=self._drain, name="console-output", daemon=True)
        self._reader.start()

    def _drain(self) -> None:
        for line in self.proc.stdout:
            self.lines.append(line)
            if len(self.lines) > KEPT_LINES:
                del self.lines[:KEPT_LINES // 2]

    def __enter__(self) -> Console:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()  # also when a test failed: a console left running would take the cores of the next

    def connection(self) -> http.client.HTTPConnection:
        return http.client.HTTPConnection("127.0.0.1", self.port, timeout=10)

    def request(self, method: str, path: str, body=None, headers=None, conn=None) -> tuple[int, dict | str]:
        own = conn is None
        conn = conn or self.connection()
        data = body if isinstance(body, (bytes, str)) or body is None else json.dumps(body)
        h = {"Content-Type": "application/json"} if method in ("POST", "PUT") else {}
        h.update(headers or {})
        conn.request(method, path, body=data, headers=h)
        r = conn.getresponse()
        raw = r.read()
        if own:
            conn.close()
        try:
            return r.status, json.loads(raw)
        except ValueError:
            return r.status, raw.decode(errors="replace")

    def hard_stop_after(self, tick: int, timeout_s: float = 2.0) -> bool:
        """Whether the loop had the hard e-stop engaged in the first published state after `tick` (an answer's
        tick: that tick's own snapshot was published before the answer)."""
        deadline = time.monotonic() + timeout_s
        while True:
            _, state = self.request("GET", "/api/state")
            if state["tick"] > tick or time.monotonic() > deadline:
                return bool(state["emergency"]["hard_stop"])
            time.sleep(0.005)

    def stop(self, sig: int = signal.SIGTERM, timeout_s: float = 30.0) -> tuple[int, str]:
        """Send `sig`, wait; (exit code, everything it printed)."""
        if self.proc.returncode is not None:
            return self.proc.returncode, "".join(self.lines)
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self._reader.join(timeout=5.0)
        return self.proc.returncode, "".join(self.lines)


def _operator(port: int, every_s: float, duration_s: float, results) -> None:
    """Presses the e-stop every `every_s` (and releases it); the latency [ms] from sending the request to the
    loop engaging it (the robot's own timestamp, on the same monotonic clock)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    latencies, errors = [], []
    end = time.monotonic() + duration_s
    time.sleep(every_s)
    while time.monotonic() < end - 0.2:
        sent = time.monotonic()
        conn.request("POST", "/api/estop", body="", headers={"Content-Type": "application/json"})
        r = conn.getresponse()
        reply = json.loads(r.read())
        if r.status == 200:
            latencies.append((reply["engaged_at_monotonic_s"] - sent) * 1e3)
        else:
            errors.append(f"estop {r.status}: {reply}")
        time.sleep(0.1)
        conn.request("POST", "/api/estop/release", body="", headers={"Content-Type": "application/json"})
        conn.getresponse().read()
        time.sleep(max(0.0, every_s - 0.1))
    conn.close()
    results.put((latencies, errors))


def run_load(console: Console, duration_s: float, pollers: int = 20, poll_hz: float = 10.0,
             commands_per_s: float = 100.0, commanders: int = 4, estop_every_s: float | None = None) -> dict:
    """`pollers` clients GET /api/state at `poll_hz`; `commanders` send `commands_per_s` commands in all (joint
    angles of the head and Stabilizer parameters, alternating); with `estop_every_s` an operator presses the
    e-stop that often and releases it. Returns the request times [ms] and the loop's timing over the run."""
    stop = threading.Event()
    state_ms: list[float] = []
    estop_ms: list[float] = []
    errors: list[str] = []
    counts = {"polls": 0, "commands": 0, "refused": 0}

    def poller() -> None:
        conn = console.connection()
        next_t = time.monotonic()
        while not stop.is_set():
            t0 = time.perf_counter()
            status, reply = console.request("GET", "/api/state", conn=conn)
            state_ms.append((time.perf_counter() - t0) * 1e3)
            if status != 200:
                errors.append(f"state {status}: {reply}")
            counts["polls"] += 1
            next_t += 1.0 / poll_hz
            time.sleep(max(0.0, next_t - time.monotonic()))
        conn.close()

    def commander(k: int) -> None:
        conn = console.connection()
        next_t = time.monotonic()
        while not stop.is_set():
            if k % 2:
                status, reply = console.request("POST", "/api/sequence/joint-angles", conn=conn, body={
                    "angles_deg": {"HEAD_JOINT0": 5.0 if k % 4 == 1 else -5.0}, "time": 0.5})
            else:
                status, reply = console.request("PUT", "/api/stabilizer/params", conn=conn,
                                                body={"cp_threshold_m": 0.04 + 0.001 * (k % 3)})
            if status == 409:
                counts["refused"] += 1  # during an e-stop
            elif status != 200:
                errors.append(f"command {status}: {reply}")
            counts["commands"] += 1
            k += 1
            next_t += commanders / commands_per_s
            time.sleep(max(0.0, next_t - time.monotonic()))
        conn.close()

    threads = [threading.Thread(target=poller) for _ in range(pollers)]
    threads += [threading.Thread(target=commander, args=(k,)) for k in range(commanders)]
    operator = None
    if estop_every_s:  # the operator is a client of its own, as a person at another browser would be
        ctx = multiprocessing.get_context("spawn")
        results = ctx.Queue()
        operator = ctx.Process(target=_operator, args=(console.port, estop_every_s, duration_s, results))
        operator.start()
    for th in threads:
        th.start()
    time.sleep(duration_s)
    stop.set()
    for th in threads:
        th.join()
    if operator is not None:
        got_ms, got_errors = results.get(timeout=60.0)
        operator.join(timeout=10.0)
        estop_ms.extend(got_ms)
        errors.extend(got_errors)
    _, timing = console.request("GET", f"/api/loop/timing?last_s={max(1.0, duration_s - 1.0):g}")
    return {"duration_s": duration_s, "polls_per_s": round(counts["polls"] / duration_s, 1),
            "commands_per_s": round(counts["commands"] / duration_s, 1), "refused_during_estop": counts["refused"],
            "state_request": percentiles_ms(state_ms), "estop_request_to_engaged": percentiles_ms(estop_ms),
            "loop": timing, "errors": errors[:10]}
