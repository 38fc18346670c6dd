"""Named places the robot knows, as world points [m] a gaze or a reach can be aimed at ([OP] II, VI): the EXPO
table's and trash box's known places (where the behaviours and the EXPO run take them to be) and every object
it has located (its latest recognition; the operator's correction wins, as it does for the behaviours)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import robot.generate as gen
from behaviors.approach_table import TABLE_CENTRE_Y_M, TABLE_NEAR_EDGE_X_M

TABLE_LOOK_IN_M = 0.15  # [m] the table's point: this far in from its near edge, on its centre line
TABLE_LOOK_ABOVE_M = 0.05  # [m] and this far above its top (the EXPO run looks there to locate the can)

#: object -> its known place (world [m]): the point of the table top the EXPO run looks at, the hole in the
#: trash box's lid. Only the objects the current scene has are offered.
KNOWN_PLACES: dict[str, tuple[float, float, float]] = {
    "table": (TABLE_NEAR_EDGE_X_M + TABLE_LOOK_IN_M, TABLE_CENTRE_Y_M, gen.EXPO_TABLE_SIZE_M[2] + TABLE_LOOK_ABOVE_M),
    "trash_box": (gen.TRASH_BOX_CENTRE_M[0], gen.TRASH_BOX_CENTRE_M[1], gen.TRASH_BOX_OUTER_M[2]),
}
#: other names an operator may type for a place
ALIASES: dict[str, str] = {"box": "trash_box"}


class UnknownPlace(LookupError):
    """The name is no place the robot knows; the message lists the ones it does."""

    def __init__(self, name: str, valid: Iterable[str]) -> None:
        shown = ", ".join(valid) or "none (locate an object first, or use a scene with a table)"
        super().__init__(f"unknown place {name!r}; valid: {shown}")
        self.name = name


@dataclass(frozen=True)
class Place:
    name: str
    position_m: tuple[float, float, float]  # world [m]
    source: str  # "known" (the scene's known place), else the recognition's: "estimated", "confirmed", "corrected"


def places(objects: Iterable[str], recognitions: Mapping[str, Mapping]) -> dict[str, Place]:
    """Every place: the known ones of the scene's `objects`, then each located object (which replaces the known
    place of the same name: where the robot saw it is better than where it was assumed to be)."""
    found = {name: Place(name, KNOWN_PLACES[name], "known") for name in objects if name in KNOWN_PLACES}
    for name, rec in recognitions.items():
        pos = rec.get("position_m")
        if pos is not None and len(pos) == 3:
            found[name] = Place(name, tuple(float(v) for v in pos), str(rec.get("status", "estimated")))
    return found


def valid_names(found: Mapping[str, Place]) -> list[str]:
    """The names an operator may type: each place, then the aliases of the places there are."""
    return [*found, *(alias for alias, name in ALIASES.items() if name in found)]


def resolve(name: str, objects: Iterable[str], recognitions: Mapping[str, Mapping]) -> Place:
    """The place called `name` (or one of its aliases); UnknownPlace listing the valid names otherwise."""
    found = places(objects, recognitions)
    place = found.get(ALIASES.get(name, name))
    if place is None:
        raise UnknownPlace(name, valid_names(found))
    return place
