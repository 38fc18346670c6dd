"""The operator service: the one door into the robot (`OperatorService`, in app.service.operator), its errors, its
verbs (app.service.verbs), the robot host that runs them and the process it lives in."""

from app.service.errors import (
    InvalidArgument,
    NotFound,
    PointTaken,
    Refused,
    ServiceError,
    Superseded,
    Unavailable,
)
from app.service.operator import OperatorService, RobotBackend
from app.service.setpoints import Sender

__all__ = ["InvalidArgument", "NotFound", "OperatorService", "PointTaken", "Refused", "RobotBackend", "Sender",
           "ServiceError", "Superseded", "Unavailable"]
