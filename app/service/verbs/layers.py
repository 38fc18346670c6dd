"""Verbs of the layers: start and stop (the AutoBalancer, the Stabilizer, a hand's impedance), their
parameters, and enabling them."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from app.service.errors import InvalidArgument, NotFound
from app.service.verbs.base import Host, RobotInfo, Verb
from controller.core.errors import InvalidCommand
from controller.core.layer import Params

#: layers that can be started and stopped, with the label messages use
STARTABLE = {"abc": "AutoBalancer", "st": "Stabilizer"}


@dataclass(frozen=True)
class StartLayer(Verb):
    name = "start_layer"
    motion = True
    layer: str

    def __post_init__(self) -> None:
        if self.layer not in STARTABLE:
            raise NotFound(f"no startable layer {self.layer!r}; startable: {', '.join(STARTABLE)}")

    def run(self, host: Host) -> str:
        host.layer(self.layer).start()
        return f"{STARTABLE[self.layer]} started"


@dataclass(frozen=True)
class StopLayer(Verb):
    name = "stop_layer"
    layer: str

    def __post_init__(self) -> None:
        if self.layer not in STARTABLE:
            raise NotFound(f"no startable layer {self.layer!r}; startable: {', '.join(STARTABLE)}")

    def run(self, host: Host) -> str:
        host.layer(self.layer).stop()
        return f"{STARTABLE[self.layer]} stopped"


@dataclass(frozen=True)
class StartImpedance(Verb):
    name = "start_impedance"
    motion = True
    limb: str

    def check(self, info: RobotInfo) -> None:
        _check_limb(info, self.limb)

    def run(self, host: Host) -> str:
        host.layer("ic").start(self.limb)
        return f"impedance control of {self.limb} started"


@dataclass(frozen=True)
class StopImpedance(Verb):
    name = "stop_impedance"
    limb: str

    def check(self, info: RobotInfo) -> None:
        _check_limb(info, self.limb)

    def run(self, host: Host) -> str:
        host.layer("ic").stop(self.limb)
        return f"impedance control of {self.limb} stopped"


def _check_limb(info: RobotInfo, limb: str) -> None:
    if limb not in info.impedance_limbs:
        raise NotFound(f"unknown limb {limb!r}; valid limbs: {', '.join(info.impedance_limbs)}")


def typed_changes(params: Params, changes: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """`changes` checked against the Params dataclass of `params`: known names, the field's type (no string
    or boolean for a number, no fraction for an integer), finite, inside the declared range and choices.
    Each rejection names the field (after `prefix`) and what is allowed. A nested Params field takes an object of
    some of its fields (or dotted names, "emergency_step.step_time_s"), checked the same way; the result names them
    dotted, flat (what SetParams records)."""
    cls = type(params)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    if not changes:
        raise InvalidArgument(prefix.rstrip(".") or "body", f"give at least one parameter; valid: {sorted(fields)}")
    changes = _grouped(params, cls.current_names(changes))
    unknown = sorted(set(changes) - set(fields))
    if unknown:
        raise InvalidArgument(prefix + unknown[0], f"unknown parameter(s) {unknown} of {cls.__name__}; "
                                                   f"valid: {sorted(fields)}")
    out: dict[str, Any] = {}
    for key, value in changes.items():
        name = prefix + key
        kind = type(getattr(params, key))
        meta = fields[key].metadata
        if issubclass(kind, Params):
            if not isinstance(value, Mapping):
                raise InvalidArgument(name, f"must be an object of some {kind.__name__} fields (got {_short(value)})")
            out.update({f"{key}.{k}": v for k, v in typed_changes(getattr(params, key), value, name + ".").items()})
            continue
        if kind is bool:
            if not isinstance(value, bool):
                raise InvalidArgument(name, f"must be true or false (got {value!r})")
        elif kind in (int, float):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InvalidArgument(name, f"must be a number (got {value!r})")
            try:
                as_float = float(value)
            except OverflowError:
                as_float = math.inf
            if not math.isfinite(as_float):
                raise InvalidArgument(name, f"must be a finite number (got {_short(value)})")
            if kind is int and not as_float.is_integer():
                raise InvalidArgument(name, f"must be an integer (got {value!r})")
            value = kind(value)
            lo, hi = meta.get("min"), meta.get("max")
            if (lo is not None and value < lo) or (hi is not None and value > hi):
                unit = meta.get("unit", "")
                raise InvalidArgument(name, f"{value:g} {unit} is outside the allowed range "
                                            f"[{'-inf' if lo is None else f'{lo:g}'}, "
                                            f"{'inf' if hi is None else f'{hi:g}'}] {unit} ({cls.__name__}.{key})")
        elif kind is str and not isinstance(value, str):
            raise InvalidArgument(name, f"must be a string (got {value!r})")
        choices = meta.get("choices")
        if choices is not None and value not in choices:
            raise InvalidArgument(name, f"{value!r} is not one of the allowed {list(choices)} ({cls.__name__}.{key})")
        out[key] = value
    try:
        params.replaced(**out)  # the dataclass's own invariants (cross-field checks)
    except InvalidCommand as exc:
        raise InvalidArgument(prefix.rstrip(".") or "body", str(exc)) from exc
    return out


def _grouped(params: Params, changes: Mapping[str, Any]) -> dict[str, Any]:
    """`changes` with the dotted names of a nested Params field ("emergency_step.step_time_s") gathered into one
    object per field, merged with an object given for it."""
    out: dict[str, Any] = {}
    for name, value in changes.items():
        head, dot, rest = name.partition(".")
        if dot and isinstance(getattr(params, head, None), Params):
            name, value = head, {rest: value}
        merge = isinstance(out.get(name), Mapping) and isinstance(value, Mapping)
        out[name] = {**out[name], **value} if merge else value
    return out


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


@dataclass(frozen=True)
class SetParams(Verb):
    """Replace some parameters of one or more layers, all or none, at one tick boundary.

    `changes`: ((owner, ((field, value), ...)), ...) with owner a layer name or "ic:<limb>"."""

    name = "set_params"
    changes: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...]

    @staticmethod
    def of(info: RobotInfo, changes: Mapping[str, Mapping[str, Any]], prefixes: Mapping[str, str] | None = None
           ) -> SetParams:
        """Checked against the robot's parameter classes; `prefixes` name the fields in errors per owner."""
        out = []
        for owner, fields in changes.items():
            if owner not in info.params:
                raise NotFound(f"no parameters {owner!r}; valid: {', '.join(info.params)}")
            prefix = (prefixes or {}).get(owner, "")
            out.append((owner, tuple(typed_changes(info.params[owner], fields, prefix).items())))
        return SetParams(tuple(out))

    def run(self, host: Host) -> dict[str, Params]:
        new = {owner: host.params(owner).replaced(**dict(fields)) for owner, fields in self.changes}
        for owner, params in new.items():
            host.set_params(owner, params)
        return new


@dataclass(frozen=True)
class GetParams(Verb):
    name = "get_params"
    recorded = False
    owners: tuple[str, ...] = ()  # empty: all

    def run(self, host: Host) -> dict[str, Params]:
        return {o: host.params(o) for o in (self.owners or host.param_owners())}


@dataclass(frozen=True)
class EnableLayers(Verb):
    """Let layers work (True) or pass their input through (False): for benchmarks and diagnosis. The KalmanFilter,
    RemoveForceOffset and HardEmergencyStopper keep estimating and guarding when disabled (the bench says which ran)."""

    name = "enable_layers"
    enabled: tuple[tuple[str, bool], ...]

    def check(self, info: RobotInfo) -> None:
        unknown = [n for n, _ in self.enabled if n not in info.chain]
        if unknown:
            raise NotFound(f"no layer(s) {unknown}; the chain has {list(info.chain)}")

    def run(self, host: Host) -> str:
        for name, on in self.enabled:
            host.layer(name).enabled = bool(on)
        return ", ".join(f"{n} {'on' if on else 'off'}" for n, on in self.enabled)
