"""`locate_trash_box`: look where the operator says (by default the trash box's known place), locate the hole
in its lid in the narrow camera's image, remember and publish its centre and yaw."""

from __future__ import annotations

from behaviors.locating import LocateObject, locate_params

#: The trash box's known place (robot/hrp2/README.md, EXPO scene): the lid top 0.60 m high at (1.4, -2.0) m.
TRASH_BOX_LOOK_M = (1.4, -2.0, 0.6)


class LocateTrashBox(LocateObject):
    name = "locate_trash_box"
    object_name = "trash_box"
    Params = locate_params(*TRASH_BOX_LOOK_M)
    summary = "Look where asked (default: the trash box's place) and locate the hole in its lid"
