"""The invariants of issue 27, checked on every answer and every published state a session sees; each
violation is kept with its invariant's number, the simulated time and what was seen."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any

from app.service.errors import Refused
from behaviors.causes import run_cause

INVARIANTS: Mapping[int, str] = {
    1: "no fall unless a push beyond the envelope came first",
    2: "every refusal and every failed or cancelled behaviour names its cause from a closed set",
    3: "an e-stop answered ok is engaged in the loop's state",
    4: "an answer that says ok was applied (where the state shows it)",
    5: "no 5xx, no controller fault, the robot process alive, no tick late by more than 2 ms when paced",
    6: "after the session, releasing the stops and `stand` bring the robot back to half-sitting unless it fell "
       "or a push beyond the envelope came",
}

#: The closed set of a refusal's `reason` (409 and the stream's acks: the service's reasons, the simulation's
#: divergence and a setpoint the robot did not acknowledge in time; 423: the operator lock)
REFUSAL_REASONS: frozenset[str] = frozenset((*Refused.REASONS, "diverged", "timeout", "locked"))
LATE_TICK_MS = 2.0  # [ms] a paced tick may start at most this late
STAND_TOLERANCE_DEG = 3.0  # [deg] every joint (grippers aside) this close to half-sitting after `stand`
GRIPPERS = ("RARM_JOINT6", "LARM_JOINT6")


@dataclasses.dataclass(frozen=True)
class Violation:
    invariant: int
    time_s: float  # [s] simulated, the console's clock
    detail: str

    def to_dict(self) -> dict[str, Any]:
        return {"invariant": self.invariant, "rule": INVARIANTS[self.invariant], "time_s": self.time_s,
                "detail": self.detail}


@dataclasses.dataclass
class Expectation:
    """What an ok answer promises the state will show by `deadline_s` [s] (simulated); `first_only`: on the first
    state at or after `from_tick` already. Voided by an action of a kind in `void_by`, a reset or a fall."""

    invariant: int
    what: str
    holds: Callable[[Mapping[str, Any]], bool]
    deadline_s: float
    void_by: frozenset[str] = frozenset()
    from_tick: int = -1
    first_only: bool = False


class Checker:
    """Feed it every answer (`answer`), every state (`state`), the runs (`run`), the pushes (`push`), the loop's
    timing (`timing`) and health (`health`); `violations` is what broke."""

    def __init__(self) -> None:
        self.violations: list[Violation] = []
        self.expectations: list[Expectation] = []
        self.pushes: list[tuple[float, float, float]] = []  # (time [s], impulse [N s], envelope [N s])
        self.fell_at: float | None = None
        self.time_s = 0.0
        self.tick = -1
        self.last_state: Mapping[str, Any] | None = None
        self._runs_seen: set[tuple[int, str]] = set()
        self.falls: list[dict[str, Any]] = []
        #: stands that did not bring the robot back after a push beyond the envelope in the stretch: listed in the
        #: report, not violations (beyond it the invariants promise nothing, as for invariant 1's falls)
        self.beyond_stands: list[dict[str, Any]] = []
        self._fault: str | None = None  # the fault the last state showed (each one is said once)
        self.runs_before: set[int] = set()  # runs a session before this one started on the same console

    def __repr__(self) -> str:
        return f"Checker(violations={len(self.violations)}, expectations={len(self.expectations)})"

    def violate(self, invariant: int, detail: str, time_s: float | None = None) -> None:
        v = Violation(invariant, round(self.time_s if time_s is None else time_s, 4), detail)
        if v not in self.violations:  # the same state seen twice says it once
            self.violations.append(v)

    # ---- what the session did -----------------------------------------------------------------------------------
    def acted(self, kind: str) -> None:
        """An action of `kind` was sent: the expectations it voids go."""
        self.expectations = [e for e in self.expectations if kind not in e.void_by]

    def reset(self) -> None:
        """The simulation was reset: a new robot, new time; the pushes and the fall before are forgotten."""
        self.expectations.clear()
        self.pushes.clear()
        self.fell_at = None
        self.tick = -1
        self.last_state = None

    def push(self, impulse_ns: float, envelope_ns: float) -> None:
        self.pushes.append((self.time_s, float(impulse_ns), float(envelope_ns)))

    def expect(self, e: Expectation) -> None:
        self.expectations.append(e)

    # ---- answers --------------------------------------------------------------------------------------------------
    def answer(self, what: str, status: int, body: Any) -> None:
        """An HTTP answer to `what` ("POST /api/estop")."""
        if status >= 500:
            self.violate(5, f"{what} answered {status}: {str(body)[:300]}")
        elif status >= 400:
            cause = self.refusal_cause(status, body)
            if cause is None:
                self.violate(2, f"{what} refused {status} without a cause from the closed set: {str(body)[:300]}")

    @staticmethod
    def refusal_cause(status: int, body: Any) -> str | None:
        """The cause a refusal names (409/423: its reason, with a detail), or None. A 404 or 422 to a request the
        grammar made valid names no cause of the closed set: the grammar or the API is wrong."""
        if not isinstance(body, Mapping) or not body.get("detail"):
            return None
        reason = body.get("reason")
        if status == 423:
            return "locked" if reason == "locked" and body.get("holder") else None
        if status == 409 and reason in REFUSAL_REASONS:
            return str(reason)
        return None

    def ack(self, what: str, ack: Mapping[str, Any]) -> None:
        """A stream's answer to one setpoint: ok, or not ok naming a reason from the closed set."""
        if ack.get("ok"):
            return
        if ack.get("reason") in REFUSAL_REASONS or (ack.get("reason") == "locked" and ack.get("holder")):
            return
        self.violate(2, f"{what}: a setpoint refused without a cause from the closed set: {dict(ack)}")

    def run(self, run: Mapping[str, Any]) -> None:
        """A behaviour run as GET /api/behaviors/runs gives it: once ended failed or cancelled, its message
        must name a cause."""
        state = run.get("state")
        if state not in ("failed", "cancelled"):
            return
        key = (int(run["id"]), state)
        if key in self._runs_seen or int(run["id"]) in self.runs_before:
            return
        self._runs_seen.add(key)
        if run_cause(str(run.get("message", ""))) is None:
            self.violate(2, f"run {run['id']} ({run.get('behavior')}) {state} without a cause from the closed set: "
                            f"{run.get('message')!r}", run.get("ended_s") or self.time_s)

    def behavior_started(self, name: str, status: int, body: Any, latched: Mapping[str, Any] | None) -> None:
        """A behaviour's start answered `status` while the last state showed the stops `latched` (its
        `emergency`): under the motion stop it must be refused naming it."""
        if latched and latched.get("motion_stop") and status == 200:
            self.violate(2, f"{name} started although the motion stop was latched "
                            f"({latched.get('motion_stop_reason')})")
        if latched and latched.get("motion_stop") and status == 409 and isinstance(body, Mapping) \
                and body.get("reason") not in ("motion_stop", "hard_stop", "fallen", "locked", "walking_stop"):
            self.violate(2, f"{name} under the motion stop refused naming {body.get('reason')!r}: {body.get('detail')}")

    # ---- states ---------------------------------------------------------------------------------------------------
    def state(self, s: Mapping[str, Any]) -> None:
        """One published state (GET /api/state)."""
        self.time_s = float(s["time"])
        self.tick = int(s["tick"])
        self.last_state = s
        fault = (s.get("emergency") or {}).get("fault")
        if fault and fault != self._fault:  # the campaign injects none: a fault from valid input is a defect
            self.violate(5, f"a controller fault: {fault}")
        self._fault = fault
        if s.get("fallen") and self.fell_at is None:
            self.fell_at = self.time_s
            beyond = [p for p in self.pushes if p[1] > p[2]]
            self.falls.append({"time_s": self.time_s, "pushes": list(self.pushes)})
            if not beyond:
                pushes = ", ".join(f"{j:.1f} N s at {t:.2f} s (envelope {e:g})" for t, j, e in self.pushes) or "none"
                self.violate(1, f"fell at {self.time_s:.3f} s with no push beyond the envelope before (pushes: "
                                f"{pushes})")
        kept = []
        for e in self.expectations:
            if s.get("fallen"):
                continue  # a fall voids what was promised
            if self.tick < e.from_tick:
                kept.append(e)
                continue
            if e.holds(s):
                continue
            if e.first_only or self.time_s > e.deadline_s:
                self.violate(e.invariant, f"{e.what} (state at {self.time_s:.3f} s, tick {self.tick})")
                continue
            kept.append(e)
        self.expectations = kept

    def timing(self, t: Mapping[str, Any]) -> None:
        """GET /api/loop/timing: when paced, no tick started more than LATE_TICK_MS late."""
        if t.get("paced") and float(t.get("lateness_max_ms") or 0.0) > LATE_TICK_MS:
            self.violate(5, f"a paced tick started {t['lateness_max_ms']:.2f} ms late (limit {LATE_TICK_MS} ms)")

    def health(self, h: Mapping[str, Any]) -> None:
        if not h.get("robot_alive"):
            self.violate(5, f"the robot process is not alive: {h.get('exit_reason')}")

    # ---- the end of a session -------------------------------------------------------------------------------------
    def back_to_half_sitting(self, stand: Mapping[str, Any] | None, joints_deg: Mapping[str, float],
                             half_sitting_deg: Mapping[str, float], fallen: bool) -> None:
        """Invariant 6: `stand` (its run, or its refusal as {state, message}) after the stops were released brought
        every joint but the grippers within STAND_TOLERANCE_DEG of half-sitting, unless the robot fell."""
        if fallen:
            return
        failure = None
        if stand is None or stand.get("state") != "succeeded":
            said = "no answer" if stand is None else f"{stand.get('state')}: {stand.get('message')}"
            failure = f"`stand` after releasing the stops did not succeed ({said})"
        else:
            off = {name: joints_deg[name] - q for name, q in half_sitting_deg.items()
                   if name not in GRIPPERS and name in joints_deg
                   and not abs(joints_deg[name] - q) <= STAND_TOLERANCE_DEG}
            if off:
                worst = sorted(off.items(), key=lambda kv: -abs(kv[1]))[:5]
                failure = "after `stand` the joints are not at half-sitting: " + ", ".join(
                    f"{n} {d:+.1f} deg" for n, d in worst)
        if failure is None:
            return
        beyond = [p for p in self.pushes if p[1] > p[2]]
        if beyond:
            self.beyond_stands.append({"time_s": round(self.time_s, 4), "detail": failure, "pushes": beyond})
        else:
            self.violate(6, failure)

