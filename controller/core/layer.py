"""The one shape every layer of the chain has: tick(ctx, ref) -> ref, params, status."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from controller.core.errors import InvalidCommand
from controller.core.types import Ports, Reference, TickContext


@dataclass(frozen=True)
class Params:
    """Base of the per-layer frozen parameter dataclasses.

    Subclasses declare fields with defaults and describe unit and range in `metadata`
    (`field(default=2.5, metadata={"unit": "s", "min": 0.0})`); `validate()` checks them once.
    """

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(f.default, Params) and not isinstance(value, type(f.default)):
                raise InvalidCommand(f"{type(self).__name__}.{f.name} must be a {type(f.default).__name__}")
            lo, hi = f.metadata.get("min"), f.metadata.get("max")
            choices = f.metadata.get("choices")
            if choices is not None and value not in choices:
                raise InvalidCommand(f"{type(self).__name__}.{f.name}={value!r}; allowed: {list(choices)}")
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                continue
            if value != value:  # NaN
                raise InvalidCommand(f"{type(self).__name__}.{f.name} is NaN")
            if lo is not None and value < lo or hi is not None and value > hi:
                raise InvalidCommand(
                    f"{type(self).__name__}.{f.name}={value!r} [{f.metadata.get('unit', '')}] "
                    f"out of range [{lo}, {hi}]"
                )

    def replaced(self, **changes: Any):
        """A validated copy with `changes`; unknown names are rejected with the valid ones listed. A nested Params
        field takes a Params, a mapping of some of its fields, or its fields as dotted names ("emergency_step.
        step_time_s"); the names of before are read as `current_names` says."""
        fields = {f.name: f for f in dataclasses.fields(self)}
        flat: dict[str, Any] = {}
        nested: dict[str, dict[str, Any]] = {}
        for name, value in self.current_names(changes).items():
            head, dot, rest = name.partition(".")
            if head in fields and isinstance(getattr(self, head), Params) and (dot or isinstance(value, Mapping)):
                nested.setdefault(head, {}).update({rest: value} if dot else value)
            else:
                flat[name] = value
        unknown = sorted(set(flat) - set(fields))
        if unknown:
            raise InvalidCommand(f"unknown parameter(s) {unknown} for {type(self).__name__}; valid: {sorted(fields)}")
        for head, sub in nested.items():
            if head in flat:
                raise InvalidCommand(f"{type(self).__name__}.{head} given whole and by field: give one of them")
            flat[head] = getattr(self, head).replaced(**sub)
        return dataclasses.replace(self, **flat)

    @classmethod
    def current_names(cls, changes: Mapping[str, Any]) -> dict[str, Any]:
        """`changes` in the current field names (a subclass that renamed fields maps the old names here, once)."""
        return dict(changes)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def describe(cls) -> list[dict[str, Any]]:
        """Field name, default, unit, range: what a GUI or schema needs to render the parameters. A nested Params
        field gives its default as a dict and its own fields' descriptions in "params"."""
        out = []
        for f in dataclasses.fields(cls):
            if isinstance(f.default, Params):
                out.append({"name": f.name, "default": f.default.to_dict(), **dict(f.metadata),
                            "params": type(f.default).describe()})
            else:
                out.append({"name": f.name, "default": f.default, **dict(f.metadata)})
        return out


def described(doc: str, unit: str | None = None) -> dict[str, str]:
    """Field metadata of a Status dataclass: what the value is, and its unit ("m", "s", "rad", "N", ...)."""
    return {"doc": doc} if unit is None else {"doc": doc, "unit": unit}


def plain(value: Any) -> Any:
    """A status value as JSON-shaped Python: dataclasses and dicts to dicts, tuples to lists (leaves not copied)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (tuple, list)):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    return value


@dataclass(frozen=True, slots=True)
class Status:
    """Base of the per-layer frozen status dataclasses a layer publishes each tick (in the snapshot).

    Fields hold plain values (bool, int, float, str, None, tuples, nested Status) and declare what they
    are in `metadata` (`field(metadata=described("capture-point error", "m"))`), so the app can generate
    the response schema of /api/state from them without per-field code.
    """

    enabled: bool = field(metadata=described(
        "the layer works; false: it passes its input through (kf, rmfo and hes still estimate and guard)"))

    def to_dict(self) -> dict[str, Any]:
        """The fields as plain dicts and lists, nested status dataclasses included."""
        return plain(self)

    @classmethod
    def describe(cls) -> list[dict[str, Any]]:
        """Field name, type, unit and description: what a schema generator needs."""
        return [{"name": f.name, "type": f.type, **dict(f.metadata)} for f in dataclasses.fields(cls)]


class SharedStatus:
    """A piece of a status() dict rebuilt only when its key changes, so consecutive snapshots share one
    object while it stays the same (every list a snapshot keeps is work for the garbage collector).
    Readers of a snapshot must not modify it."""

    __slots__ = ("_key", "_value")
    _UNSET = object()

    def __init__(self) -> None:
        self._key: Any = SharedStatus._UNSET
        self._value: Any = None

    def get(self, key: Any, build: Callable[[], Any]) -> Any:
        if key != self._key:
            self._value = build()
            self._key = key
        return self._value


class Layer:
    """A stage of the real-time chain.

    `tick` reads the measured state in `ctx` and the upstream reference and returns the reference for
    the next layer. A disabled layer returns its input unchanged (hrpsys `qRef -> q`).
    Commands are plain methods, called only by the loop at a tick boundary.
    """

    name: ClassVar[str] = "layer"
    description: ClassVar[str] = ""
    #: the layer the loop engages on a fault or a fall: it has engage(q_rad, reason) and an `engaged` flag
    safe_stop: ClassVar[bool] = False

    def __init__(self) -> None:
        self.enabled = True

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        raise NotImplementedError

    def after_write(self, ports: Ports) -> None:
        """Called by the loop once this tick's command is written to the servos, before the next tick (and its
        commands): work for the next tick that needs only `ports` (this tick's, the next one's last_ports) and the
        layer's own state, done off the sensor-to-actuator path. It may prepare, never change what the next tick
        or a reader sees: the next tick adopts the result only if its inputs are still the ones it was made from.
        Not called for a disabled layer nor after a faulted tick; an exception is a fault (safe stop)."""

    def status(self) -> Status:
        """The layer's frozen Status (a subclass per layer), published in every snapshot."""
        return Status(enabled=self.enabled)
