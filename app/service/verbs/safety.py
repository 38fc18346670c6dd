"""Verbs of the stops: the hard e-stop's release and the EmergencyStopper's motion stop (hrpsys
EmergencyStopperService)."""

from __future__ import annotations

from dataclasses import dataclass

from app.service.verbs.base import Host, Verb


@dataclass(frozen=True)
class ReleaseEstop(Verb):
    name = "release_estop"
    setpoints_before: int = 0  # the console's newest setpoint number when the release was sent
    #: [s] the console's time.monotonic() when the release was sent (one clock for the machine's processes): a
    #: press handled after it is not released by it. None: not checked (a replay: its clock is another run's)
    sent_monotonic_s: float | None = None

    def run(self, host: Host) -> str:
        host.release_estop(self.setpoints_before, self.sent_monotonic_s)
        return "hard e-stop released"


@dataclass(frozen=True)
class StopMotion(Verb):
    name = "stop_motion"

    def run(self, host: Host) -> str:
        host.layer("es").stop_motion()
        return "planned motion stopped"


@dataclass(frozen=True)
class ReleaseMotion(Verb):
    name = "release_motion"

    def run(self, host: Host) -> str:
        host.layer("es").release_motion()
        return "motion stop released"
