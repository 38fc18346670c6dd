"""The hard e-stop while walking, over the gait cycle: the robot walking (goVelocity) is e-stopped at a phase of its
gait cycle, held, released and watched. One run's spec, the grid, the run itself and the summary table
(`hrp2-console study estop-walking`)."""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any

from app.lab.study.push_walking import CYCLE_S, SETTLE_S, WARMUP_S, walk_to_phase

#: Bump when a change makes stored results stale (what a run does or what it reports).
STORE_FORMAT = 1
WATCH_S = 6.0  # [s] after the release
#: the walks: (forward [m/s], left [m/s], turning [deg/s]); the sideways one is soak seed 10705's
WALKS: dict[str, tuple[float, float, float]] = {
    "0.2": (0.2, 0.0, 0.0), "back": (-0.1, 0.0, 0.0), "side": (0.0, 0.1, 0.0), "turn": (0.1, 0.0, 10.0)}
HOLDS_S = (0.3, 1.25, 3.0)  # [s] from the press to the release: while it lands, just after, long after


@dataclass(frozen=True)
class EstopSpec:
    """One run: the walk (a key of WALKS), the phase of the gait cycle the e-stop is pressed at (0..1 from a right
    touchdown) and how long it holds before the release [s]."""

    walk: str
    phase: float
    hold_s: float
    watch_s: float = WATCH_S

    def __post_init__(self) -> None:
        if self.walk not in WALKS:
            raise ValueError(f"unknown walk {self.walk!r}; choose from {', '.join(WALKS)}")
        if not (0.0 <= self.phase < 1.0 and self.hold_s > 0.0 and self.watch_s > 0.0):
            raise ValueError(f"phase in [0, 1), hold > 0 and watch > 0 expected, got {self}")

    def to_dict(self) -> dict[str, Any]:
        return {"format": STORE_FORMAT, "study": "estop-walking", "walk": self.walk, "phase": self.phase,
                "hold_s": self.hold_s, "watch_s": self.watch_s}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> EstopSpec:
        return cls(d["walk"], float(d["phase"]), float(d["hold_s"]), float(d["watch_s"]))

    def key(self) -> str:
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def expected_sim_s(self) -> float:
        return SETTLE_S + WARMUP_S + 1.0 + self.phase * CYCLE_S + self.hold_s + self.watch_s


def grid(walks, phases: int, holds_s) -> list[EstopSpec]:
    return [EstopSpec(w, k / phases, float(h)) for w in walks for k in range(phases) for h in holds_s]


RESULT_FIELDS = ("outcome", "fall_after_release_s", "support_at_press", "frozen_after_s", "support_frozen",
                 "cp_error_at_release_m", "peak_cp_error_m", "flag", "error")


def _estop_run(s: EstopSpec) -> tuple[dict[str, Any], float]:
    from app.service import OperatorService
    from app.service.local import LocalRobot

    robot = LocalRobot("default")
    service = OperatorService(robot)
    robot.run_for(SETTLE_S)
    vx, vy, vtheta_deg = WALKS[s.walk]
    walk_to_phase(robot, vx, vy, math.radians(vtheta_deg), s.phase)
    support_at_press = robot.host.observation.layers["abc"].support
    service.estop()
    t_press = robot.host.observation.time_s
    frozen_after = support_frozen = None
    while robot.host.observation.time_s < t_press + s.hold_s - 1e-9:
        obs = robot.step()
        if frozen_after is None and obs.layers["hes"].stopping is None:
            frozen_after, support_frozen = obs.time_s - t_press, obs.layers["abc"].support
    cp_at_release = float(robot.host.observation.layers["st"].cp_error_norm)
    service.release_estop()
    t_release = robot.host.observation.time_s
    peak, flag, fall_t = cp_at_release, False, None
    for _ in range(int(round(s.watch_s / robot.loop.dt_control_s))):
        obs = robot.step()
        peak = max(peak, float(obs.layers["st"].cp_error_norm))
        flag = flag or bool(obs.layers["st"].emergency)
        if obs.fallen:
            fall_t = obs.time_s - t_release
            break
    return {"outcome": "fell" if fall_t is not None else "stood", "fall_after_release_s": fall_t,
            "support_at_press": support_at_press, "frozen_after_s": frozen_after, "support_frozen": support_frozen,
            "cp_error_at_release_m": cp_at_release, "peak_cp_error_m": peak, "flag": flag,
            "error": None}, robot.host.observation.time_s


def run_estop(spec: dict[str, Any]) -> dict[str, Any]:
    """Run `spec` (EstopSpec.to_dict()) in a fresh simulation: {"key", "result", "timing"} (run.run_timed)."""
    from app.lab.study.run import run_timed

    return run_timed(EstopSpec.from_dict(spec), _estop_run, RESULT_FIELDS)


def summary_markdown(rows: list[tuple[EstopSpec, dict[str, Any]]]) -> str:
    """Per walk and hold: runs, stood, frozen on both feet, the CP error at the release and its peak after it."""
    lines = ["| walk | hold [s] | runs | stood | frozen on both feet | flag after the release | "
             "CP error at release, max [mm] | peak CP error after, max [mm] | errors |",
             "|---|---|---|---|---|---|---|---|---|"]
    keys = list(dict.fromkeys((s.walk, s.hold_s) for s, _ in rows))
    for walk, hold in keys:
        rs = [r for s, r in rows if (s.walk, s.hold_s) == (walk, hold)]
        ok = [r for r in rs if r["outcome"] != "error"]
        at, peak = (f"{max(r[f] for r in ok) * 1e3:.1f}" if ok else "-"
                    for f in ("cp_error_at_release_m", "peak_cp_error_m"))
        lines.append(f"| {walk} | {hold:g} | {len(rs)} | {sum(r['outcome'] == 'stood' for r in rs)} | "
                     f"{sum(r['support_frozen'] == 'both' for r in rs)} | {sum(bool(r['flag']) for r in rs)} | "
                     f"{at} | {peak} | {len(rs) - len(ok)} |")
    fell = [(s, r) for s, r in rows if r["outcome"] == "fell"]
    lines += ["", f"fell: {len(fell)} of {len(rows)}" + "".join(
        f"\n- {s.walk}, phase {s.phase:g}, hold {s.hold_s:g} s (pressed in {r['support_at_press']}): "
        f"{r['fall_after_release_s']:.2f} s after the release" for s, r in fell)]
    return "\n".join(lines) + "\n"
