"""The push map (issue 26): its runs on a backend (stored, resumable), each run's outcome beside the LIP's
capturability of its push, the counts, the worst cases and one heat map per walk."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from app.lab.study.capturability import Capturability, Lip, largest_capturable_ns, push_capturability
from app.lab.study.push_walking import PUSH_S, WALKS, PushSpec, walk_label
from app.lab.study.store import RunStore
from app.lab.study.study import PhaseStats, execute


def hrp2_lip() -> Lip:
    """HRP-2's LIP as simulated at the start (half-sitting, soles on the floor at z = 0): the robot's whole mass
    (BODY's subtree) and its COM height (58.0 kg, 0.811 m: the AutoBalancer's numbers too)."""
    from app.service.local import LocalRobot

    robot = LocalRobot("default")
    body = robot.plant.model.body("BODY").id
    return Lip(float(robot.plant.model.body_subtreemass[body]), float(robot.host.observation.truth.com_world[2]))


@dataclass(frozen=True)
class Cell:
    """One run of the map and what the LIP says of its push."""

    spec: PushSpec
    result: dict[str, Any]
    capture: Capturability

    @property
    def outcome(self) -> str:  # "stood", "fell" or "error"
        return self.result["outcome"]

    @property
    def capturable(self) -> bool:
        return self.capture.steps is not None


def cells_of(specs: Sequence[PushSpec], store: RunStore, lip: Lip) -> list[Cell]:
    """The specs the store holds, with their capturability (speed and phase as the spec's walk's)."""
    out = []
    for s in specs:
        if s.key() in store:
            speed = WALKS[s.walk][0]
            result = store.get(s.key())["result"]
            cap = push_capturability(s.impulse_ns, math.radians(s.direction_deg), s.phase, speed, lip, push_s=PUSH_S,
                                     cp_from_sole_xy=result.get("cp_push_rel_xy"))
            out.append(Cell(s, result, cap))
    return out


def run_map(specs: Sequence[PushSpec], backend, store: RunStore, lip: Lip, stream: TextIO | None = None
            ) -> tuple[list[Cell], PhaseStats]:
    stats = execute("push map", specs, backend, store, stream)
    return cells_of(specs, store, lip), stats


@dataclass(frozen=True)
class Counts:
    runs: int
    stood: int
    fell: int
    fell_capturable: int  # inside the LIP's boundary: the controller's
    fell_not_capturable: int  # outside it: physics (with at most one step)
    stood_not_capturable: int  # the robot did better than the one-step LIP (a second step, the hip, ...)
    errors: int


def counts(cells: Sequence[Cell]) -> Counts:
    fell = [c for c in cells if c.outcome == "fell"]
    return Counts(len(cells), sum(c.outcome == "stood" for c in cells), len(fell), sum(c.capturable for c in fell),
                  sum(not c.capturable for c in fell),
                  sum(c.outcome == "stood" and not c.capturable for c in cells),
                  sum(c.outcome == "error" for c in cells))


def capture_margin_m(c: Cell) -> float:
    """How far inside the LIP's boundary the push was [m] (the better of the ankle's and the step's margins)."""
    step = c.capture.step_margin_m
    return max(c.capture.ankle_margin_m, -math.inf if step is None else step)


def summary_markdown(cells: Sequence[Cell], lip: Lip, stats: PhaseStats | None = None, worst: int = 10) -> str:
    lines = [f"LIP: mass {lip.mass_kg:.1f} kg, COM height {lip.com_height_m:.3f} m, omega {lip.omega_1_s:.2f} 1/s",
             "", "| walk | impulse [N s] | runs | stood | fell | fell, capturable (controller) | "
             "fell, not capturable (physics) | stood, not capturable | errors |",
             "|---|---|---|---|---|---|---|---|---|"]
    walks = list(dict.fromkeys(c.spec.walk for c in cells))
    for w in walks:
        for j in sorted({c.spec.impulse_ns for c in cells if c.spec.walk == w}):
            n = counts([c for c in cells if c.spec.walk == w and c.spec.impulse_ns == j])
            lines.append(f"| {walk_label(w)} | {j:g} | {n.runs} | {n.stood} | {n.fell} | {n.fell_capturable} | "
                         f"{n.fell_not_capturable} | {n.stood_not_capturable} | {n.errors} |")
    n = counts(cells)
    lines.append(f"| all | | {n.runs} | {n.stood} | {n.fell} | {n.fell_capturable} | {n.fell_not_capturable} | "
                 f"{n.stood_not_capturable} | {n.errors} |")
    bad = sorted((c for c in cells if c.outcome == "fell" and c.capturable), key=capture_margin_m, reverse=True)
    if bad:
        lines += ["", f"Falls the LIP calls capturable, deepest inside its boundary first (of {len(bad)}):", "",
                  "| walk | J [N s] | direction [deg] | phase | support at push | LIP | margin [mm] | "
                  "fell after [s] | peak CP error [mm] | flag | walking stop | emergency steps |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for c in bad[:worst]:
            r = c.result
            lines.append(f"| {walk_label(c.spec.walk)} | {c.spec.impulse_ns:g} | {c.spec.direction_deg:g} | "
                         f"{c.spec.phase:.4g} | {r['support_at_push']} | {c.capture.label} | "
                         f"{1e3 * capture_margin_m(c):.0f} | {r['fall_after_push_s']:.2f} | "
                         f"{1e3 * r['peak_cp_error_m']:.0f} | {'yes' if r['flag'] else 'no'} | "
                         f"{'yes' if r['walking_stop'] else 'no'} | {r['emergency_steps']} |")
    errors = sorted({c.result["error"] for c in cells if c.outcome == "error"})
    if errors:
        lines += ["", "Errors: " + "; ".join(errors)]
    if stats is not None and stats.runs:
        lines += ["", f"This invocation: {stats.runs} runs ({stats.skipped} found stored), {stats.sim_s:.0f} s "
                  f"simulated in {stats.wall_s:.0f} s of wall time."]
    return "\n".join(lines) + "\n"


def plot_push_map(cells: Sequence[Cell], walk: str, path: Path, lip: Lip | None = None, title: str | None = None
                  ) -> Path:
    """One panel per impulse: phase of the gait cycle across, push direction up; a cell green (stood) or red
    (fell), grey (error), its LIP verdict as 0 / 1 (steps), hatched and outlined where one step cannot capture.
    With `lip`, two more panels: the largest impulse the LIP captures with the ankles and with one step."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    mine = [c for c in cells if c.spec.walk == walk]
    impulses = sorted({c.spec.impulse_ns for c in mine})
    directions = sorted({c.spec.direction_deg for c in mine})
    phases = sorted({c.spec.phase for c in mine})
    colour = {"stood": "#4caf50", "fell": "#e53935", "error": "#9e9e9e"}
    panels = len(impulses) + (2 if lip is not None else 0)
    cols = min(2, panels)
    rows = -(-panels // cols)
    fig, grid_axes = plt.subplots(rows, cols, figsize=(0.45 * len(phases) * cols + 1.2, 3.6 * rows + 0.6),
                                  squeeze=False, constrained_layout=True)
    axes = [list(grid_axes.flat)]
    for ax in axes[0][panels:]:
        ax.set_visible(False)
    axes[0] = axes[0][:panels]
    if lip is not None:
        speed = WALKS[walk][0]
        measured = {c.spec.phase: c.result.get("cp_push_rel_xy") for c in mine}  # the same walk at each phase
        for ax, steps, name in zip(axes[0][len(impulses):], (0, 1), ("the ankles", "one step"), strict=True):
            bound = np.array([[largest_capturable_ns(math.radians(d), ph, speed, lip, steps, push_s=PUSH_S,
                                                     cp_from_sole_xy=measured[ph])
                               for ph in phases] for d in directions])
            ax.imshow(bound, origin="lower", cmap="viridis", vmin=0.0, vmax=100.0, aspect="auto")
            for (r, k), v in np.ndenumerate(bound):
                ax.text(k, r, f"{v:.0f}", ha="center", va="center", fontsize=6,
                        color="white" if v < 60 else "black")
            ax.set_title(f"LIP: the largest impulse [N s] {name} capture", fontsize=9)
    for ax in axes[0]:
        ax.set_xlim(-0.5, len(phases) - 0.5)
        ax.set_ylim(-0.5, len(directions) - 0.5)
        step = max(1, len(phases) // 8)
        ax.set_xticks(range(0, len(phases), step), [f"{phases[k]:.2g}" for k in range(0, len(phases), step)],
                      fontsize=7)
        ax.set_yticks(range(len(directions)), [_direction_name(d) for d in directions], fontsize=7)
        ax.set_xlabel("gait phase (0: right touchdown, 0.5: left)", fontsize=8)
        ax.set_ylabel("push direction (robot frame)", fontsize=8)
    for ax, j in zip(axes[0][:len(impulses)], impulses, strict=True):
        for c in (c for c in mine if c.spec.impulse_ns == j):
            x, y = phases.index(c.spec.phase), directions.index(c.spec.direction_deg)
            ax.add_patch(Rectangle((x - 0.5, y - 0.5), 1, 1, fc=colour[c.outcome], ec="white", lw=0.5))
            if not c.capturable:
                ax.add_patch(Rectangle((x - 0.5, y - 0.5), 1, 1, fill=False, hatch="///", ec="black", lw=0.0))
            else:
                ax.text(x, y, str(c.capture.steps), ha="center", va="center", fontsize=7, color="white")
        grid = np.full((len(directions), len(phases)), np.nan)
        for c in (c for c in mine if c.spec.impulse_ns == j):
            grid[directions.index(c.spec.direction_deg), phases.index(c.spec.phase)] = float(c.capturable)
        _outline(ax, grid)
        n = counts([c for c in mine if c.spec.impulse_ns == j])
        ax.set_title(f"{j:g} N s: stood {n.stood}, fell {n.fell} (of which capturable: {n.fell_capturable})",
                     fontsize=9)
    fig.suptitle(title or f"push map, walking {walk_label(walk)}, 0.1 s pushes on BODY\ngreen stood, red fell; 0 / 1: "
                 "the steps the LIP needs; hatched and outlined: not capturable with one step", fontsize=10)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _direction_name(deg: float) -> str:
    names = {0.0: "fwd", 45.0: "fwd-left", 90.0: "left", 135.0: "back-left", 180.0: "back", 225.0: "back-right",
             270.0: "right", 315.0: "fwd-right"}
    return names.get(round(deg % 360.0, 6), f"{deg:g} deg")


def _outline(ax, capturable: np.ndarray) -> None:
    """Black lines along the cell edges between capturable (1) and not (0) cells: the LIP's boundary."""
    rows, cols = capturable.shape
    for r in range(rows):
        for k in range(cols):
            v = capturable[r, k]
            if np.isnan(v):
                continue
            if k + 1 < cols and not np.isnan(capturable[r, k + 1]) and capturable[r, k + 1] != v:
                ax.plot([k + 0.5, k + 0.5], [r - 0.5, r + 0.5], color="black", lw=1.8)
            if r + 1 < rows and not np.isnan(capturable[r + 1, k]) and capturable[r + 1, k] != v:
                ax.plot([k - 0.5, k + 0.5], [r + 0.5, r + 0.5], color="black", lw=1.8)


def map_paths(out_dir: Path, walks: Sequence[str]) -> dict[str, Path]:
    paths = {"store": out_dir / "runs.jsonl", "summary": out_dir / "summary.md"}
    paths |= {f"map {w}": out_dir / f"push_map_{w.replace('.', '')}.png" for w in walks}
    return paths
