"""Finished study runs, one JSON line each (spec, result, timing) keyed by the run's key: a restart skips them."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any


class RunStore:
    """An append-only JSONL file. Each line is written and flushed to disk whole, so a study killed mid-run
    leaves at most a torn last line, which `load` skips (that run is simply run again)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.records: dict[str, dict[str, Any]] = {}
        self.skipped_lines = 0
        self.load()

    def __repr__(self) -> str:
        return f"RunStore({str(self.path)!r}, {len(self.records)} runs)"

    def load(self) -> None:
        self.records.clear()
        self.skipped_lines = 0
        self._torn_end = False
        if not self.path.exists():
            return
        text = self.path.read_text(encoding="utf-8")
        self._torn_end = bool(text) and not text.endswith("\n")
        for line in text.splitlines():
            try:
                record = json.loads(line)
                self.records[record["key"]] = record
            except (ValueError, KeyError, TypeError):
                self.skipped_lines += 1

    def __contains__(self, key: str) -> bool:
        return key in self.records

    def __len__(self) -> int:
        return len(self.records)

    def get(self, key: str) -> dict[str, Any]:
        return self.records[key]

    def add(self, record: dict[str, Any]) -> None:
        """`record`: {"key", "spec", "result", "timing"}."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        line = json.dumps(record, sort_keys=True, separators=(",", ":"))
        with open(self.path, "a", encoding="utf-8") as fh:
            if self._torn_end:
                fh.write("\n")  # after a torn line: start afresh
                self._torn_end = False
            fh.write(line + "\n")
            fh.flush()
            os.fsync(fh.fileno())
        self.records[record["key"]] = record
