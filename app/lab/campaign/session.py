"""One seeded random-operator session against a real console (`hrp2-console --headless`), through its public
API only: HTTP, /ws/operator and /ws/telemetry, as the page and scripts use them; the checker sees every
answer and every state."""

from __future__ import annotations

import contextlib
import dataclasses
import http.client
import json
import logging
import math
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import PurePath
from typing import Any

from websockets.sync.client import ClientConnection, connect

from app.lab.campaign.checker import Checker, Expectation, Violation
from app.lab.campaign.grammar import Action, actions_for, push_request
from behaviors.stand import FOOT_DOWN_MAX_S

log = logging.getLogger(__name__)

WARM_UP_S = 2.5  # [s] simulated after a reset: the AutoBalancer and the Stabilizer blended in
STREAM_EVERY_S = 0.05  # [s] simulated between two setpoints of a stream (the page sends 50 Hz of wall time)
RUNS_EVERY_S = 0.25  # [s] simulated between two reads of the behaviour runs
HEALTH_EVERY_S = 5.0  # [s] simulated between two reads of the robot's health
#: [s] wall, between two turns of the session's loop: the robot publishes its state every 20 ms of wall time, so a
#: turn (this and a GET of ~2 ms) still reads each; at 3 ms it read each ~4 times, and a session ran 12 % slower
POLL_SLEEP_S = 0.012
WAIT_WALL_S = 60.0  # [s] wall: the longest a wait for the simulation may take (a stalled console fails it)
SETTLE_S = 3.0  # [s] simulated after `stand` before the joints are compared (a fall after it is the session's)
SECOND_CLIENT = "second-operator"
STAND_TRIES = 4  # `stand` is asked this often at the end while a stop that ends by itself refuses it
STAND_RETRY_S = 2.0  # [s] simulated between two tries
SELF_ENDING = ("collision", "walking_stop")  # the stops that end by themselves (no release verb)
#: actions after which what an earlier ok promised may no longer show (the expectation is void)
STOPS = frozenset({"estop", "motion_stop", "walk_stop", "walk_emergency_stop", "reset", "push", "push_beyond"})
FEET = ("rfoot", "lfoot")
WALK_SHOWN_S = 2.0  # [s] an accepted walk shows in the state within this (invariant 4); a push till then: walking
WALK_VOIDS = STOPS | {"go_velocity", "go_pos", "behavior", "stick", "closed_tab", "compete", "cancel"}


@dataclasses.dataclass
class SessionResult:
    seed: int
    seconds: float  # [s] simulated, asked
    actions: list[Action]
    violations: list[Violation]
    counts: Counter  # actions sent, by kind
    simulated_s: float  # [s] simulated, done (with the warm-ups and the end's checks)
    wall_s: float
    falls: list[dict[str, Any]]
    pushes: list[tuple[float, float, float]]
    trace: list[dict[str, Any]] = dataclasses.field(default_factory=list)
    recordings: dict[str, bytes] = dataclasses.field(default_factory=dict)  # MCAP of the stretches that violated
    beyond_stands: list[dict[str, Any]] = dataclasses.field(default_factory=list)  # Checker.beyond_stands

    def to_dict(self) -> dict[str, Any]:
        return {"seed": self.seed, "seconds": self.seconds, "actions": [a.to_dict() for a in self.actions],
                "violations": [v.to_dict() for v in self.violations], "counts": dict(self.counts),
                "simulated_s": round(self.simulated_s, 3), "wall_s": round(self.wall_s, 3), "falls": self.falls,
                "pushes": self.pushes, "trace": self.trace, "beyond_stands": self.beyond_stands}


class _Stream:
    """A stick stream on one WebSocket: a setpoint every STREAM_EVERY_S until `end_s`, then a zero (or the tab
    closes without one)."""

    def __init__(self, ws: ClientConnection, body: dict[str, Any], end_s: float, zero: bool, close: bool,
                 name: str) -> None:
        self.ws, self.body, self.end_s, self.zero, self.close, self.name = ws, body, end_s, zero, close, name
        self.sent_s = -math.inf

    def zero_body(self) -> dict[str, Any]:
        z = {k: v for k, v in self.body.items() if k != "linear" and k != "angular"}
        return {**z, "linear": [0.0, 0.0, 0.0], "angular": [0.0, 0.0, 0.0]}


class StateUnavailable(Exception):
    """GET /api/state answered something else than the state document."""

    def __init__(self, status: int, body: Any) -> None:
        super().__init__(f"GET /api/state answered {status}: {str(body)[:300]}")


class ConsoleSilent(Exception):
    """A request the console did not answer within the connection's timeout (not sent again: it may have acted)."""


class Session:
    """Drives one session on the console listening on `port`; `run()` returns its SessionResult."""

    def __init__(self, port: int, seed: int, seconds: float, catalogue: Mapping[str, Sequence[Mapping[str, Any]]],
                 actions: Sequence[Action] | None = None, defaults: Mapping[str, Any] | None = None,
                 record: bool = False) -> None:
        self.port, self.seed, self.seconds = port, int(seed), float(seconds)
        # each stretch between resets is one recorded session (MCAP; a replay starts from a reset): (file name,
        # the violations before it); a stretch with a violation is kept with the finding
        self.record = record
        self.segments: list[tuple[str, int]] = []
        self.recordings: dict[str, bytes] = {}
        self.actions = list(actions) if actions is not None else actions_for(seed, seconds, catalogue)
        self.defaults = defaults
        self.checker = Checker()
        self.counts: Counter = Counter()
        self.conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
        self.origin = f"http://127.0.0.1:{port}"
        self.elapsed_s = 0.0  # [s] simulated since the session began, across resets
        self.simulated_s = 0.0
        self._last_time: float | None = None
        self.state: dict[str, Any] = {}
        self.streams: dict[str, _Stream] = {}  # by name: "main:<point>", "tab-<k>", "other-<k>"
        self._foot_until_s = -math.inf  # [s] session time a streamed foot may still be operated until
        self._walk_until_s = -math.inf  # [s] session time an accepted walk may still not show in the state read
        self.main_ws: ClientConnection | None = None
        self.watchers: list[tuple[ClientConnection, float]] = []
        self.lock: tuple[str, float] | None = None  # (the second client's lease token, until [s])
        self.runs: list[int] = []
        self._next = {"runs": 0.0, "health": 0.0}
        self._k = 0
        self.trace: list[dict[str, Any]] = []  # what was sent (not the reads) and answered, in order

    def __repr__(self) -> str:
        return f"Session(seed={self.seed}, seconds={self.seconds}, actions={len(self.actions)})"

    # ---- HTTP -------------------------------------------------------------------------------------------------
    def request(self, method: str, path: str, body: Any = None, headers: Mapping[str, str] | None = None,
                check: bool = True) -> tuple[int, Any]:
        data = None if body is None else json.dumps(body)
        h = {"Content-Type": "application/json"} if method in ("POST", "PUT", "DELETE") else {}
        h.update(headers or {})
        for attempt in (0, 1):
            try:
                self.conn.request(method, path, body=data, headers=h)
                r = self.conn.getresponse()
                raw = r.read()
                break
            except TimeoutError:
                self.conn.close()
                raise ConsoleSilent(f"{method} {path}: no answer within {self.conn.timeout:g} s") from None
            except (ConnectionError, http.client.HTTPException):
                self.conn.close()
                if attempt:
                    raise
        try:
            answer = json.loads(raw)
        except ValueError:
            answer = raw.decode(errors="replace")
        if check:
            self.checker.answer(f"{method} {path}", r.status, answer)
        if method != "GET":
            self.trace.append({"time_s": self.checker.time_s, "request": f"{method} {path}", "body": body,
                               "status": r.status, "answer": str(answer)[:200]})
        return r.status, answer

    def poll(self, check: bool = True) -> dict[str, Any]:
        status, s = self.request("GET", "/api/state", check=check)
        if status != 200 or not isinstance(s, dict) or "time" not in s:
            raise StateUnavailable(status, s)
        t = float(s["time"])
        if self._last_time is not None and t >= self._last_time:
            self.elapsed_s += t - self._last_time
            self.simulated_s += t - self._last_time
        self._last_time = t
        self.state = s
        if check:
            self.checker.state(s)
        return s

    def wait_until(self, predicate, timeout_s: float, what: str) -> bool:
        """Poll (and serve the streams) until `predicate(state)` or `timeout_s` [s] simulated went by."""
        start, wall = self.elapsed_s, time.monotonic()
        while True:
            s = self.poll()
            if predicate(s):
                return True
            if self.elapsed_s - start > timeout_s or time.monotonic() - wall > WAIT_WALL_S:
                if what:
                    log.info("seed %d: %s not reached in %.1f s", self.seed, what, timeout_s)
                return False
            self.serve()
            time.sleep(POLL_SLEEP_S)

    def _foot_operated(self, now_s: float) -> bool:
        """A foot operated (the AutoBalancer's lift in any phase but idle), or one streamed recently enough that the
        state read may not show it yet."""
        abc = (self.state.get("layers") or {}).get("abc") or {}
        return abc.get("foot_lift") in ("shifting", "lifted", "lowering", "returning") or now_s < self._foot_until_s

    def _walking(self, now_s: float) -> bool:
        """Walking, or a walk accepted recently enough that the state read may not show it yet (soak seed 11023: an
        18 N s push, drawn from the standing envelope, 0 s after a goVelocity was accepted, in its first step)."""
        return bool(self.state.get("walking")) or now_s < self._walk_until_s

    def emergency(self) -> dict[str, Any]:
        return dict(self.state.get("emergency") or {})

    # ---- WebSockets -----------------------------------------------------------------------------------------------
    def ws(self, path: str) -> ClientConnection:
        return connect(f"ws://127.0.0.1:{self.port}{path}", origin=self.origin, open_timeout=10.0)

    def _drain(self, stream: _Stream) -> None:
        while True:
            try:
                msg = stream.ws.recv(timeout=0)
            except TimeoutError:
                return
            except Exception:  # noqa: BLE001 - a closed stream says nothing more
                return
            ack = json.loads(msg)
            self.checker.ack(f"stream {stream.name}", ack)

    def serve(self) -> None:
        """Send each stream's setpoint when due, read the acks and the watchers, end what is over."""
        for key, st in list(self.streams.items()):
            if self.elapsed_s >= st.end_s:
                if st.zero:
                    with contextlib.suppress(Exception):
                        st.ws.send(json.dumps(st.zero_body()))
                        self._drain(st)
                if st.close:
                    with contextlib.suppress(Exception):
                        st.ws.close()
                del self.streams[key]
                continue
            if self.elapsed_s - st.sent_s >= STREAM_EVERY_S:
                try:
                    st.ws.send(json.dumps(st.body))
                except Exception as exc:  # noqa: BLE001
                    self.checker.violate(5, f"stream {st.name} closed by the console: {exc}")
                    del self.streams[key]
                    continue
                st.sent_s = self.elapsed_s
            self._drain(st)
        for ws, end_s in list(self.watchers):
            with contextlib.suppress(TimeoutError):
                while True:
                    msg = json.loads(ws.recv(timeout=0))
                    if "time" not in msg:
                        self.checker.violate(4, f"/ws/telemetry sent no state: {str(msg)[:200]}")
            if self.elapsed_s >= end_s:
                ws.close()
                self.watchers.remove((ws, end_s))
        if self.lock is not None and self.elapsed_s >= self.lock[1]:
            self.request("DELETE", "/api/operator/lock", headers={"X-Lock-Token": self.lock[0]})
            self.lock = None
        if self.elapsed_s >= self._next["runs"]:
            self._next["runs"] = self.elapsed_s + RUNS_EVERY_S
            _, runs = self.request("GET", "/api/behaviors/runs")
            for run in runs if isinstance(runs, list) else []:
                self.checker.run(run)
        if self.elapsed_s >= self._next["health"]:
            self._next["health"] = self.elapsed_s + HEALTH_EVERY_S
            _, h = self.request("GET", "/api/health")
            self.checker.health(h)

    # ---- the session ------------------------------------------------------------------------------------------------
    def run(self) -> SessionResult:
        wall = time.monotonic()
        try:
            self._run()
        except StateUnavailable as exc:  # the session cannot go on without the state: a finding, not a crash
            self.checker.violate(5, f"the state document is unavailable: {exc}")
        except ConsoleSilent as exc:  # nor without answers (a soak piece crashed whole on one in stop 43)
            self.checker.violate(5, f"the console stopped answering: {exc}")
        finally:
            self.close()
        c = self.checker
        return SessionResult(self.seed, self.seconds, self.actions, list(c.violations), self.counts,
                             self.simulated_s, time.monotonic() - wall, c.falls, [], self.trace, self.recordings,
                             c.beyond_stands)

    def _run(self) -> None:
        """Start, act and check for the session's seconds, then the end-of-session check."""
        self.start()
        half_sitting = {n: j["meas_deg"] for n, j in self.state["joints"].items()}
        pending = list(self.actions)
        while self.elapsed_s < self.seconds:
            while pending and pending[0].at_s <= self.elapsed_s:
                self.act(pending.pop(0))
            self.serve()
            time.sleep(POLL_SLEEP_S)
            self.poll()
        self.finish(half_sitting)
        if self.record:
            self.keep_recordings()

    def start(self) -> None:
        """A fresh robot: the defaults of the parameters, a reset, the warm-up."""
        _, runs = self.request("GET", "/api/behaviors/runs")  # the console's earlier sessions' runs are theirs
        self.checker.runs_before = {int(r["id"]) for r in runs} if isinstance(runs, list) else set()
        if self.defaults:
            self.request("PUT", "/api/params", self.defaults)
        self.reset_and_warm_up(first=True)
        self.elapsed_s = 0.0

    def reset_and_warm_up(self, first: bool = False) -> int:
        """Reset and wait for the warm-up; `first`: the state before is the previous session's, not checked."""
        before = self.poll(check=not first)
        if self.record:
            self._stop_recording()
            status, body = self.request("POST", "/api/sessions/start",
                                        {"name": f"campaign-{self.seed}-{len(self.segments)}"})
            if status == 200:
                self.segments.append((PurePath(body["recording"]["path"]).name, len(self.checker.violations)))
        else:
            status, body = self.request("POST", "/api/sim/reset", {"scene": "default"})
        if status != 200:
            return status
        self.checker.reset()
        self._last_time = None
        wall = time.monotonic()
        while True:
            # until the time goes back the state is the old simulation's: a fall there is not the new robot's (seed
            # 10618: a robot fallen before the reset counted as a fall without a push)
            s = self.poll(check=False)
            if s["tick"] < before["tick"] or s["time"] < before["time"]:
                break
            if time.monotonic() - wall > 10.0:
                self.checker.violate(4, f"a reset answered ok, and the state's time goes on from {before['time']}")
                return status
            time.sleep(POLL_SLEEP_S)
        self.checker.reset()
        self.wait_until(lambda st: st["time"] >= WARM_UP_S, WARM_UP_S + 1.0, "the warm-up")
        return status

    def _stop_recording(self) -> None:
        if self.segments and self.request("GET", "/api/sessions")[1].get("recording"):
            self.request("POST", "/api/sessions/stop")

    def keep_recordings(self) -> None:
        """Finish the recording; download each stretch in which a violation was seen (`recordings`)."""
        self._stop_recording()
        ends = [n for _, n in self.segments[1:]] + [len(self.checker.violations)]
        for (name, before), after in zip(self.segments, ends, strict=True):
            if after > before:
                self.conn.request("GET", f"/api/sessions/{name}")
                r = self.conn.getresponse()
                data = r.read()
                if r.status == 200:
                    self.recordings[name] = data

    def close(self) -> None:
        for st in self.streams.values():
            with contextlib.suppress(Exception):
                st.ws.close()
        for ws, _ in self.watchers:
            with contextlib.suppress(Exception):
                ws.close()
        if self.main_ws is not None:
            with contextlib.suppress(Exception):
                self.main_ws.close()
        self.conn.close()

    # ---- one action ----------------------------------------------------------------------------------------------
    def act(self, a: Action) -> None:
        self.counts[a.kind] += 1
        self.trace.append({"time_s": self.checker.time_s, "action": a.to_dict(),
                           "walking": self.state.get("walking"), "emergency": self.emergency()})
        self.checker.acted(a.kind)
        p, now, e = a.params, self.elapsed_s, self.emergency()
        t = self.checker.time_s
        if a.kind in ("stick", "closed_tab", "compete"):
            self._k += 1
            if a.kind == "stick":
                if self.main_ws is None:
                    self.main_ws = self.ws("/ws/operator?client=campaign")
                name, ws, zero, close = f"main:{p['body']['point']}", self.main_ws, True, False
            else:
                name = f"{'tab' if a.kind == 'closed_tab' else 'other'}-{self._k}"
                ws, zero, close = self.ws(f"/ws/operator?client={name}"), a.kind == "compete", True
            self.streams[name] = _Stream(ws, dict(p["body"]), now + float(p["duration_s"]), zero, close, name)
            if p["body"]["point"] in FEET:  # the foot comes down after its stream, unless the state says sooner
                self._foot_until_s = max(self._foot_until_s, now + float(p["duration_s"]) + FOOT_DOWN_MAX_S)
            elif p["body"]["point"] == "walk":
                self._walk_until_s = max(self._walk_until_s, now + WALK_SHOWN_S)
        elif a.kind == "go_velocity":
            status, _ = self.request("POST", "/api/walk/go-velocity", dict(p))
            if status == 200 and any(abs(float(v)) > 0.02 for v in p.values()):
                self._walk_until_s = now + WALK_SHOWN_S
                self._expect_walking(t, "goVelocity answered ok and the robot does not walk")
        elif a.kind == "go_pos":
            status, _ = self.request("POST", "/api/walk/go-pos", dict(p))
            if status == 200 and (abs(p["x"]) > 0.02 or abs(p["y"]) > 0.02 or abs(p["theta_deg"]) > 2):
                self._walk_until_s = now + WALK_SHOWN_S
                self._expect_walking(t, "goPos answered ok and the robot does not walk")
        elif a.kind == "walk_stop":
            self.request("POST", "/api/walk/stop")
        elif a.kind == "walk_emergency_stop":
            status, _ = self.request("POST", "/api/walk/emergency-stop")
            if status == 200:
                self.checker.expect(Expectation(
                    4, "the emergency walking stop answered ok and the robot walks on without it",
                    lambda s: bool(s["emergency"]["walking_stop"]) or not s["walking"], t + 0.5,
                    frozenset({"reset"})))
        elif a.kind == "behavior":
            status, body = self.request("POST", f"/api/behaviors/{p['name']}", dict(p["params"]))
            self.checker.behavior_started(p["name"], status, body, e)
            if status == 200:
                self.runs.append(int(body["id"]))
                code, run = self.request("GET", f"/api/behaviors/runs/{body['id']}")
                if code != 200:
                    self.checker.violate(4, f"{p['name']} answered run {body['id']}, which GET does not know: {run}")
        elif a.kind == "cancel":
            if self.runs:
                run_id = self.runs[-1]
                status, body = self.request("POST", f"/api/behaviors/runs/{run_id}/cancel")
                if status == 200 and body.get("state") == "running":
                    self.checker.violate(4, f"the cancel of run {run_id} answered ok and the run still runs")
        elif a.kind == "estop":
            status, body = self.request("POST", "/api/estop")
            if status == 200:
                self.checker.expect(Expectation(
                    3, f"the e-stop answered ok at tick {body.get('tick')} and the first state after shows it "
                       "not engaged",
                    lambda s: bool(s["emergency"]["hard_stop"]), t + 1.0, frozenset({"estop_release", "reset"}),
                    from_tick=int(body.get("tick", -1)) + 1, first_only=True))  # as Console.hard_stop_after
        elif a.kind == "estop_release":
            status, _ = self.request("POST", "/api/estop/release")
            if status == 200:
                self.checker.expect(Expectation(
                    4, "the e-stop's release answered ok and the e-stop stays engaged",
                    lambda s: not s["emergency"]["hard_stop"], t + 1.0, frozenset({"estop", "reset"})))
        elif a.kind == "motion_stop":
            status, _ = self.request("POST", "/api/motion/stop")
            if status == 200:
                self.checker.expect(Expectation(
                    4, "the motion stop answered ok and the state shows no motion stop",
                    lambda s: bool(s["emergency"]["motion_stop"]), t + 0.5, frozenset({"motion_release", "reset"})))
        elif a.kind == "motion_release":
            status, _ = self.request("POST", "/api/motion/release")
            if status == 200:
                stopped_at = e.get("motion_stop_time")
                self.checker.expect(Expectation(
                    4, "the motion stop's release answered ok and the same motion stop stays latched",
                    lambda s: not s["emergency"]["motion_stop"] or s["emergency"]["motion_stop_time"] != stopped_at,
                    t + 1.0, frozenset({"motion_stop", "reset"})))
        elif a.kind in ("push", "push_beyond"):
            body, impulse, envelope = push_request(a, walking=self._walking(now),
                                                   frozen=bool(self.state["emergency"].get("hard_stop")),
                                                   foot=self._foot_operated(now))
            status, _ = self.request("POST", "/api/sim/push", body)
            if status == 200:
                self.checker.push(impulse, envelope)
        elif a.kind == "params":
            status, _ = self.request("PUT", p["path"], {p["field"]: p["value"]})
            if status == 200:
                _, got = self.request("GET", p["path"])
                value = (got.get("params", got) if isinstance(got, dict) else {}).get(p["field"])
                if value is None or abs(float(value) - float(p["value"])) > 0.0051:
                    self.checker.violate(4, f"PUT {p['path']} {p['field']}={p['value']} answered ok and GET gives "
                                            f"{value}")
        elif a.kind == "reset":
            self.runs.clear()
            self.reset_and_warm_up()
        elif a.kind == "watch":
            self.watchers.append((self.ws("/ws/telemetry?rate_hz=10"), now + float(p["duration_s"])))
        elif a.kind == "take_lock":
            if self.lock is None:
                status, body = self.request("POST", "/api/operator/lock", {"client": SECOND_CLIENT})
                if status == 200:
                    self.lock = (body["token"], now + float(p["duration_s"]))
                    _, held = self.request("GET", "/api/operator/lock")
                    if held.get("holder") != SECOND_CLIENT:
                        self.checker.violate(4, f"the lock answered ok to {SECOND_CLIENT} and is held by {held}")

    def _expect_walking(self, t: float, what: str) -> None:
        # (or a stop did it: the hard e-stop, the walking stop, the capture-point flag, which refuses a walk not yet
        # begun; soak seed 10306: a goVelocity accepted 0.14 s after a push, before the push's flag rose)
        self.checker.expect(Expectation(
            4, what, lambda s: bool(s["walking"]) or s["emergency"]["hard_stop"] or s["emergency"]["walking_stop"]
            or bool(s["emergency"].get("flag")), t + WALK_SHOWN_S, WALK_VOIDS))

    # ---- the end: invariant 6 ------------------------------------------------------------------------------------
    def finish(self, half_sitting: Mapping[str, float]) -> None:
        """Stop every stream and second client, release the stops, run `stand`, compare with half-sitting."""
        for st in self.streams.values():
            st.end_s = -math.inf
        self.serve()
        for ws, _ in self.watchers:
            ws.close()
        self.watchers.clear()
        if self.lock is not None:
            self.request("DELETE", "/api/operator/lock", headers={"X-Lock-Token": self.lock[0]})
            self.lock = None
        for run_id in self.runs:
            self.request("POST", f"/api/behaviors/runs/{run_id}/cancel")
        self.poll()
        self.checker.expectations.clear()  # what the session's last answers promised is left unchecked
        _, t = self.request("GET", "/api/loop/timing")
        self.checker.timing(t)
        _, h = self.request("GET", "/api/health")
        self.checker.health(h)
        if self.state.get("fallen"):
            return
        if self.emergency().get("hard_stop"):
            self.request("POST", "/api/estop/release")
            self.wait_until(lambda s: not s["emergency"]["hard_stop"], 2.0, "the e-stop's release")
        self.request("POST", "/api/walk/stop")
        self.wait_until(lambda s: not s["walking"] and not s["emergency"]["walking_stop"], 20.0, "the walk's end")
        if self.emergency().get("motion_stop"):  # refused while the flag is up: it would latch again
            self.wait_until(lambda s: not s["emergency"]["flag"], 6.0, "the CP flag down")
            self.request("POST", "/api/motion/release")
            self.wait_until(lambda s: not s["emergency"]["motion_stop"], 6.0, "the motion stop's release")
        # as an operator would: `stand` walks, and no walk starts while the flag is up (seed 1003 asked at once)
        self.wait_until(lambda s: not s["emergency"]["flag"], 6.0, "the CP flag down")
        stand = None
        for _ in range(STAND_TRIES):  # a stop that ends by itself (the collision hold) may refuse it a while
            status, body = self.request("POST", "/api/behaviors/stand", {})
            if status == 200 or not isinstance(body, dict) or body.get("reason") not in SELF_ENDING:
                break
            self.wait_until(lambda s: False, STAND_RETRY_S, "")
        if status == 200:
            run_id = int(body["id"])
            self.wait_until(lambda s: self._run_over(run_id), 15.0, "stand")
            _, stand = self.request("GET", f"/api/behaviors/runs/{run_id}")
        else:  # the refusal's own words in the finding
            stand = {"state": f"refused ({status})", "message": body.get("detail") if isinstance(body, dict) else body}
        self.wait_until(lambda s: False, SETTLE_S, "")
        self.checker.back_to_half_sitting(stand, {n: j["meas_deg"] for n, j in self.state["joints"].items()},
                                          half_sitting, bool(self.state.get("fallen")))

    def _run_over(self, run_id: int) -> bool:
        _, run = self.request("GET", f"/api/behaviors/runs/{run_id}")
        return not isinstance(run, dict) or run.get("state") != "running"

