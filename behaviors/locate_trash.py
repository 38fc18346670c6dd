"""`locate_trash`: look where the operator says (by default the floor 1 m ahead), find the piece of trash of
unknown shape by colour segmentation in the narrow camera's image ([OP] VI, Fig. 8), remember and publish its
centre (x, y) and top height."""

from __future__ import annotations

from behaviors.locating import LocateObject, locate_params

#: By default the floor 1 m ahead of the start, a little above it.
FLOOR_LOOK_M = (1.0, 0.0, 0.1)


class LocateTrash(LocateObject):
    name = "locate_trash"
    object_name = "trash"
    Params = locate_params(*FLOOR_LOOK_M)
    summary = "Look where asked (default: the floor ahead) and find the trash by its colour (no model)"
