"""Exceptions owned by the perception package; each message says what would have worked."""


class PerceptionError(Exception):
    """Base class of every error perception raises on purpose."""


class InvalidImage(PerceptionError, ValueError):
    """Images, depth, intrinsics or a pose do not fit together (shape, dtype, values)."""
