"""`locate_can`: look where the operator says (by default the near part of the table, whose place is known),
locate the 300 ml can in the narrow camera's image, remember and publish where it is."""

from __future__ import annotations

from behaviors.locating import LocateObject, locate_params

#: The table's known place (robot/hrp2/README.md, EXPO scene): near edge 2.0 m ahead of the start, 0.70 m high;
#: by default the robot looks 0.15 m in from the edge, at can height.
TABLE_LOOK_M = (2.15, 0.0, 0.75)


class LocateCan(LocateObject):
    name = "locate_can"
    object_name = "can"
    Params = locate_params(*TABLE_LOOK_M)
    summary = "Look where asked (default: the table) and locate the can (head camera, no ground truth)"
