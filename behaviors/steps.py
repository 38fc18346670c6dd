"""The behaviours a sequence may hold as its steps (every behaviour but the sequence itself), by name, and one
built from plain (JSON) parameters."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from behaviors.approach_table import ApproachTable
from behaviors.base import Behavior, params_from
from behaviors.follow_arc import FollowArc
from behaviors.grasp import Grasp
from behaviors.locate_can import LocateCan
from behaviors.locate_handle import LocateHandle
from behaviors.locate_trash import LocateTrash
from behaviors.locate_trash_box import LocateTrashBox
from behaviors.look_at import LookAt
from behaviors.open_door import OpenDoor
from behaviors.reach import Reach
from behaviors.recognise import Recognise
from behaviors.release import Release
from behaviors.squat import Squat
from behaviors.stand import Stand
from behaviors.take_can import TakeCan
from behaviors.throw_can import ThrowCan
from behaviors.walk_to import WalkTo
from controller.core.errors import UnknownName

STEPS: dict[str, type[Behavior]] = {cls.name: cls for cls in (
    Stand, Squat, LookAt, WalkTo, Reach, Grasp, Release, Recognise, LocateCan, LocateHandle, LocateTrash,
    LocateTrashBox, ApproachTable, TakeCan, ThrowCan, FollowArc, OpenDoor)}


def make_from(classes: Mapping[str, type[Behavior]], name: str, params: Mapping[str, Any] | None = None,
              prefix: str = "params.") -> Behavior:
    """The behaviour `name` of `classes` with `params` checked against its Params class (UnknownName lists the
    valid names, InvalidCommand names the field)."""
    try:
        cls = classes[name]
    except KeyError:
        raise UnknownName(f"unknown behaviour {name!r}; valid: {sorted(classes)}") from None
    return cls(params_from(cls.Params, dict(params or {}), prefix))
