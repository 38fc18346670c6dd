"""Invariant 5's memory bound: the resident memory of a console (its process and the robot process under it),
read from /proc after each session, and the growth allowed between a worker's first session and its last."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

#: [MB] a console may grow by at most this much from the end of its first session to the end of its last; the
#: first session carries the imports, the caches and the first behaviours' warm-up
GROWTH_BOUND_MB = 150.0

__all__ = ["GROWTH_BOUND_MB", "growth_violations", "tree_rss_mb"]


def _children(pid: int, proc: Path) -> list[int]:
    kids: list[int] = []
    for task in (proc / str(pid) / "task").glob("*"):
        try:
            kids += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            continue
    return kids


def _rss_kb(pid: int, proc: Path) -> int:
    try:
        for line in (proc / str(pid) / "status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


def tree_rss_mb(pid: int, proc: Path = Path("/proc")) -> float | None:
    """Resident memory [MB] of `pid` and all its descendants; None where /proc is not there (not Linux)."""
    if not (proc / str(pid)).exists():
        return None
    total_kb, todo, seen = 0, [pid], set()
    while todo:
        p = todo.pop()
        if p in seen:
            continue
        seen.add(p)
        total_kb += _rss_kb(p, proc)
        todo += _children(p, proc)
    return total_kb / 1024.0


def growth_violations(results: Sequence[Mapping[str, Any]], bound_mb: float = GROWTH_BOUND_MB) -> list[dict]:
    """For each worker (`worker`, `rss_mb` of each session's result, in the order it ran them, `order`), a
    violation of invariant 5 when its last session ended more than bound_mb above its first."""
    by_worker: dict[int, list[Mapping[str, Any]]] = {}
    for r in sorted(results, key=lambda r: r.get("order", 0)):
        if r.get("rss_mb") is not None:
            by_worker.setdefault(int(r.get("worker", 0)), []).append(r)
    found = []
    for worker, rs in sorted(by_worker.items()):
        grew = rs[-1]["rss_mb"] - rs[0]["rss_mb"]
        if len(rs) > 1 and grew > bound_mb:
            found.append({"seed": rs[-1]["seed"], "invariant": 5, "time_s": 0.0,
                          "detail": f"console {worker}'s memory grew {grew:.0f} MB over {len(rs)} sessions "
                                    f"({rs[0]['rss_mb']:.0f} to {rs[-1]['rss_mb']:.0f} MB; bound {bound_mb:g} MB)"})
    return found
