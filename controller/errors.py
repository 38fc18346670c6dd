"""Exceptions owned by the controller package; each message says what would have worked."""


class ControllerError(Exception):
    """Base class of every error the controller raises on purpose."""


class InvalidCommand(ControllerError, ValueError):
    """A command's arguments are invalid (wrong name, shape, range); nothing was changed."""


class InvalidState(ControllerError):
    """A command is valid but not now (e.g. stopping what is not running)."""


class LayerFault(ControllerError):
    """A layer failed inside the tick; the loop stopped the robot safely and reports this."""
