"""The closed set of causes a failed or cancelled run names (issue 27's invariant 2): read from its message, so
that the API reports it with the run (`cause`) and the operator page can offer the one action that resolves it."""

from __future__ import annotations

import re
from collections.abc import Mapping

#: each cause and the (case-insensitive) pattern of the words a run's message names it with, first match wins
RUN_CAUSES: Mapping[str, str] = {
    "stop": r"motion stop|walking stop|e-stop",
    "cancel": r"cancelled by the operator",
    "reset": r"the simulation was reset",
    "fall": r"\bfell\b|fallen|a fall",
    "lock": r"operator lock",
    "limit": r"IK limited|joint limit|from its limit|reaches its limit|collision|out of reach|unreachable|"
             r"accuracy limit",
    "timeout": r"overran its nominal duration|\btimeout\b",
    "state": r"the robot is walking|is lifted \(its operational point\)|the capture-point flag is up|"
             r"re-planned by another command",
    "perception": r"not in the image|not seen|closed on nothing|slipped|short of open",
}


def run_cause(message: str) -> str | None:
    """The cause a run's message names, from RUN_CAUSES, or None."""
    for cause, pattern in RUN_CAUSES.items():
        if re.search(pattern, message or "", re.IGNORECASE):
            return cause
    return None
