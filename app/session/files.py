"""Session files in the sessions folder: the names a client may give (checked strictly: a plain file name, no
path), new names from the clock, and the listing."""

from __future__ import annotations

import datetime
import re
from pathlib import Path

#: a session's file name as a client gives it: letters, digits, '_', '-', '.', starting with a letter or a digit,
#: ending in .mcap (appended when left out); never a path (no '/', and it cannot be '.' or '..': it starts with a
#: letter or a digit)
NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,58}")
SUFFIX = ".mcap"
#: the same rule as a JSON-schema pattern, for the OpenAPI document (with the optional suffix)
NAME_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,58}(\.mcap)?$"


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
