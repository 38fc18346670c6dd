"""Session files in the sessions folder: the names a client may give (checked strictly: a plain file name, no
path), new names from the clock, the listing, and the retention rule."""

from __future__ import annotations

import datetime
import logging
import re
from collections.abc import Iterable
from pathlib import Path

log = logging.getLogger(__name__)

#: a session's file name as a client gives it: letters, digits, '_', '-', '.', starting with a letter or a digit,
#: ending in .mcap (appended when left out); never a path (no '/', and it cannot be '.' or '..': it starts with a
#: letter or a digit)
NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,58}")
SUFFIX = ".mcap"
#: the same rule as a JSON-schema pattern, for the OpenAPI document (with the optional suffix)
NAME_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,58}(\.mcap)?$"
#: the retention rule's defaults: the sessions folder keeps at most this many files and this many bytes (a session
#: is about 1.1 GB an hour)
KEEP_COUNT = 20
KEEP_BYTES = 4 * 1024**3


class BadName(ValueError):
    """A session name that is not a plain file name: what is allowed."""


def checked_name(name: str) -> str:
    """`name` as a file name in the sessions folder (".mcap" appended when missing); BadName otherwise."""
    if not isinstance(name, str):
        raise BadName(f"must be a string (got {name!r})")
    stem = name[:-len(SUFFIX)] if name.endswith(SUFFIX) else name
    if not NAME_RE.fullmatch(stem):
        raise BadName(f"{name[:80]!r} is not a session name: 1-59 letters, digits, '_', '-' or '.', starting with a "
                      f"letter or a digit (no path), optionally ending in {SUFFIX}")
    return stem + SUFFIX


def new_session_name(now: datetime.datetime | None = None) -> str:
    """session-YYYYmmdd-HHMMSS.mcap (local time)."""
    now = now or datetime.datetime.now()
    return f"session-{now:%Y%m%d-%H%M%S}{SUFFIX}"


def free_name(folder: str | Path, name: str | None = None) -> str:
    """`name` (checked) or a new one from the clock, with -2, -3 ... added while it exists in `folder`."""
    base = checked_name(name) if name is not None else new_session_name()
    stem = base[:-len(SUFFIX)]
    folder = Path(folder)
    candidate, k = base, 1
    while (folder / candidate).exists():
        k += 1
        candidate = f"{stem}-{k}{SUFFIX}"
    return candidate


def list_sessions(folder: str | Path) -> list[dict]:
    """The session files in `folder`, newest first: name, size [bytes], modified (UNIX time [s])."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    out = []
    for path in folder.glob(f"*{SUFFIX}"):
        if path.is_file() and NAME_RE.fullmatch(path.name[:-len(SUFFIX)]):
            st = path.stat()
            out.append({"name": path.name, "bytes": st.st_size, "modified_s": round(st.st_mtime, 3)})
    return sorted(out, key=lambda d: (-d["modified_s"], d["name"]))


def retention_rule(max_count: int, max_bytes: int) -> str:
    """The rule in words, for the help and the logs."""
    return (f"at most {max_count} session files and {max_bytes / 1024**2:g} MB together: when the console starts "
            "and when a session starts, the oldest are removed (never the one being recorded)")


def prune_sessions(folder: str | Path, max_count: int, max_bytes: int, keep: Iterable[str | Path] = ()) -> list[str]:
    """Remove the oldest session files of `folder` until at most `max_count` remain and they hold at most
    `max_bytes` [bytes] together. The files in `keep` (the one being recorded, one still being finished) are
    counted (in this folder, even before their writer has made them) but never removed. The names removed,
    oldest first."""
    folder = Path(folder)
    kept = {Path(p).resolve() for p in keep}
    sessions = list_sessions(folder)  # newest first
    listed = {(folder / s["name"]).resolve() for s in sessions}
    count = len(sessions) + sum(1 for p in kept - listed if p.parent == folder.resolve())
    total = sum(s["bytes"] for s in sessions)
    removed = []
    for s in reversed(sessions):
        if count <= max_count and total <= max_bytes:
            break
        path = folder / s["name"]
        if path.resolve() in kept:
            continue
        try:
            path.unlink(missing_ok=True)
        except OSError as exc:
            log.warning("session %s could not be removed: %s", path, exc)
            continue
        count, total = count - 1, total - s["bytes"]
        removed.append(s["name"])
    if removed:
        log.warning("sessions removed by the retention rule (%s): %s", retention_rule(max_count, max_bytes),
                    ", ".join(removed))
    return removed
