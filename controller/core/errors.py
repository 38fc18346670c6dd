"""Exceptions owned by the controller package; each message says what would have worked."""


class ControllerError(Exception):
    """Base class of every error the controller raises on purpose."""


class InvalidCommand(ControllerError, ValueError):
    """A command's arguments are invalid (wrong name, shape, range); nothing was changed."""


class Unreachable(InvalidCommand):
    """A target no posture within the joint limits reaches (the closest one is stated)."""


class UnknownName(InvalidCommand, LookupError):
    """A name (frame, link, group) the model does not have; the message gives valid ones."""


class InvalidState(ControllerError):
    """A command is valid but not now (e.g. stopping what is not running)."""
