"""The object models the robot knows [OP VI]: the 300 ml can and the trash box (its own copy, not the scene's)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class CanModel:
    """A drink can standing upright: a vertical cylinder."""

    diameter_m: float = 0.065  # [OP VI]
    height_m: float = 0.107  # 300 ml at 65 mm diameter (robot/hrp2/README.md)

    @property
    def radius_m(self) -> float:
        return self.diameter_m / 2


@dataclass(frozen=True, slots=True)
class TrashBoxModel:
    """A box whose horizontal lid (the coloured part) has a rectangular hole in its middle."""

    hole_m: tuple[float, float] = (0.28, 0.12)  # long, short side [OP VI]
    lid_m: tuple[float, float] = (0.45, 0.30)  # the lid's outer long and short side, hole centred
    lid_height_m: float = 0.60  # lid top above the floor


CAN = CanModel()
TRASH_BOX = TrashBoxModel()

#: A recognition's status beyond the operator's "confirmed" / "corrected": the robot holds the object (take_can)
#: or saw where it landed (throw_can); the page shows no Confirm for these.
HELD = "held"
IN_BOX = "in the box"
OUT_OF_BOX = "out of the box"
NOT_ON_THE_TABLE = (HELD, IN_BOX, OUT_OF_BOX)
