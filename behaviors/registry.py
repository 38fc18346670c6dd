"""The behaviours by name, and a behaviour built from plain (JSON) parameters."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from behaviors.base import Behavior
from behaviors.sequence import Sequence
from behaviors.steps import STEPS, make_from

#: every behaviour: the ones a sequence may hold, and the sequence
BEHAVIORS: dict[str, type[Behavior]] = {**STEPS, Sequence.name: Sequence}


def make(name: str, params: Mapping[str, Any] | None = None, prefix: str = "params.") -> Behavior:
    """The behaviour `name` with `params` checked against its Params class (InvalidCommand names the field)."""
    return make_from(BEHAVIORS, name, params, prefix)
