"""`locate_handle`: look where the operator says (by default the fridge's door at the handle's height), locate the
door's handle and the door's turn in the narrow camera's image, remember and publish them (for `open_door`)."""

from __future__ import annotations

from behaviors.locating import LocateObject, locate_params

#: The fridge's usual place (robot/scene_fridge.py): the handle about 0.5 m ahead, 0.20 m to the right, at its top
#: (0.95 m): the head pitches down no further at that distance.
HANDLE_LOOK_M = (0.50, -0.20, 0.95)


class LocateHandle(LocateObject):
    name = "locate_handle"
    object_name = "fridge_handle"
    Params = locate_params(*HANDLE_LOOK_M)
    summary = "Look where asked (default: the fridge's door) and locate its handle (head camera, no ground truth)"
