"""Verbs of the session recording: start and stop recording an MCAP session."""

from __future__ import annotations

from dataclasses import dataclass

from app.service.errors import InvalidArgument
from app.service.verbs.base import Host, Verb


@dataclass(frozen=True)
class StartRecording(Verb):
    """Record a session to `path` (an MCAP file the robot process writes) from a fresh simulation: with
    `reset`, the simulation is reset first (same scene); without, the robot must be at its first tick."""

    name = "start_recording"
    recorded = False
    path: str
    reset: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.path, str) or not self.path.endswith(".mcap"):
            raise InvalidArgument("path", f"must be a path ending in .mcap (got {self.path!r})")

    def run(self, host: Host) -> dict:
        return host.start_recording(self.path, reset=self.reset)


@dataclass(frozen=True)
class StopRecording(Verb):
    """End the session being recorded; the result is its status once the file is finished."""

    name = "stop_recording"
    recorded = False

    def run(self, host: Host) -> dict:
        return host.stop_recording()
