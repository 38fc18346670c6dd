"""Perception from the robot's own images: colour segmentation, depth back-projection, model fits (numpy/scipy)."""

from behaviors.perception.errors import InvalidImage, PerceptionError
from behaviors.perception.locate import Recognition, locate_can, locate_trash_box
from behaviors.perception.models import CAN, TRASH_BOX, CanModel, TrashBoxModel

__all__ = ["CAN", "TRASH_BOX", "CanModel", "InvalidImage", "PerceptionError", "Recognition", "TrashBoxModel",
           "locate_can", "locate_trash_box"]
