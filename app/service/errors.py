"""The operator service's own errors: each says what went wrong and what would have worked."""

from __future__ import annotations


class ServiceError(Exception):
    """Base of every error the operator service raises on purpose."""

    status = 500  # the HTTP status a web front end answers with


class InvalidArgument(ServiceError, ValueError):
    """A verb's argument is wrong (name, type, range); nothing was sent to the robot."""

    status = 422

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}")
        self.field = field
        self.message = message

    def __reduce__(self):  # crosses the robot process's pipe
        return type(self), (self.field, self.message)


class Refused(ServiceError):
    """A valid verb that cannot take effect now; `reason` names what is in the way."""

    status = 409

    #: why a verb can be refused, and what ends it
    REASONS = ("hard_stop", "fallen", "collision", "motion_stop", "walking_stop", "reach", "state", "point_taken",
               "superseded")

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason

    def __reduce__(self):  # crosses the robot process's pipe
        return type(self), (self.reason, str(self))


class PointTaken(Refused):
    """A setpoint for an operational point another client streams to (first come, until its stream stops)."""

    def __init__(self, point: str, owner: str, message: str) -> None:
        super().__init__("point_taken", message)
        self.point = point
        self.owner = owner  # the streaming client's display name

    def __reduce__(self):
        return type(self), (self.point, self.owner, str(self))


class Superseded(Refused):
    """A setpoint replaced by another client's newer one before the robot applied it."""

    def __init__(self, point: str, by: str | None, message: str) -> None:
        super().__init__("superseded", message)
        self.point = point
        self.by = by  # the other client's display name (None: not known any more)

    def __reduce__(self):
        return type(self), (self.point, self.by, str(self))


class NotFound(ServiceError, LookupError):
    """The verb names something that does not exist (a layer, a limb, an experiment); lists what does."""

    status = 404


class Unavailable(ServiceError):
    """The robot process is not running or did not answer in time; the console keeps serving."""

    status = 503
