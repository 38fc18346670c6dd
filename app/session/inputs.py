"""A session's inputs as JSON and back: the operator service's verbs (every field, floats exact), the streamed
setpoints and the e-stop. Only known classes are rebuilt (the verbs, Footstep, StepParams, Setpoint), through
their own constructors and checks, so a session file cannot make a replay run anything else (a Setpoint's ranges
are checked where it is applied: the operation layer acknowledges one out of them "invalid").

Tagged JSON: a tuple is an array; a list {"$list": [...]}; a dict {"$dict": [[key, value], ...]}; a dataclass
{"$type": name, "fields": {...}}; a non-finite float {"$float": "nan" | "inf" | "-inf"}."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np


class Unencodable(TypeError):
    """A value a session cannot hold (e.g. the function of a `Call` verb): the input is recorded as not
    replayable."""


class BadInput(ValueError):
    """A recorded input that does not rebuild: an unknown class or field, or one its own checks refuse."""


_REGISTRY: dict[str, type] | None = None


def registry() -> dict[str, type]:
    """The classes a session may hold, by name."""
    global _REGISTRY
    if _REGISTRY is None:
        from app.service import verbs
        from app.service.setpoints import Setpoint
        from controller.walking.footsteps import StepParams

        classes = {c.__name__: c for c in vars(verbs).values()
                   if isinstance(c, type) and issubclass(c, verbs.Verb) and dataclasses.is_dataclass(c)}
        classes.pop("Call", None)  # a function: never rebuilt
        classes.update(Footstep=verbs.Footstep, StepParams=StepParams, Setpoint=Setpoint)
        _REGISTRY = classes
    return _REGISTRY


def encode(value: Any) -> Any:
    """`value` as tagged JSON (Unencodable for anything else)."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else {"$float": repr(v)}
    if isinstance(value, tuple):
        return [encode(v) for v in value]
    if isinstance(value, list):
        return {"$list": [encode(v) for v in value]}
    if isinstance(value, Mapping):
        return {"$dict": [[encode(k), encode(v)] for k, v in value.items()]}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        name = type(value).__name__
        if registry().get(name) is not type(value):
            raise Unencodable(f"{name} is not a class a session can hold")
        return {"$type": name, "fields": {f.name: encode(getattr(value, f.name))
                                          for f in dataclasses.fields(value) if f.init}}
    raise Unencodable(f"a {type(value).__name__} cannot be recorded")


def decode(doc: Any) -> Any:
    """The value `encode` gave `doc` for, rebuilt through its class's constructor (BadInput if it does not)."""
    if doc is None or isinstance(doc, (bool, int, float, str)):
        return doc
    if isinstance(doc, list):
        return tuple(decode(v) for v in doc)
    if not isinstance(doc, Mapping) or len(doc) not in (1, 2):
        raise BadInput(f"not a tagged value: {str(doc)[:80]}")
    if "$list" in doc:
        return [decode(v) for v in doc["$list"]]
    if "$dict" in doc:
        return {decode(k): decode(v) for k, v in doc["$dict"]}
    if "$float" in doc:
        return float(doc["$float"])
    if "$type" in doc:
        cls = registry().get(doc["$type"])
        if cls is None:
            raise BadInput(f"unknown class {doc['$type']!r} in a session input")
        fields = {k: decode(v) for k, v in dict(doc.get("fields") or {}).items()}
        try:
            return cls(**fields)
        except Exception as exc:  # noqa: BLE001 - the class's own checks (InvalidArgument, TypeError)
            raise BadInput(f"{doc['$type']} does not rebuild: {exc}") from None
    raise BadInput(f"not a tagged value: {str(doc)[:80]}")


def outcome_of(result: Any = None, error: BaseException | None = None) -> dict:
    """What a verb gave: {"ok": true, "result"?} (plain results only) or {"ok": false, "error", "reason"?,
    "message"}."""
    if error is not None:
        out = {"ok": False, "error": type(error).__name__, "message": str(error)}
        reason = getattr(error, "reason", None)
        if isinstance(reason, str):
            out["reason"] = reason
        return out
    out: dict[str, Any] = {"ok": True}
    if result is None or isinstance(result, (bool, int, str)) or (isinstance(result, float) and math.isfinite(result)):
        out["result"] = result
    return out


def same_outcome(recorded: Mapping, replayed: Mapping) -> bool:
    """Whether a replayed input ended as the recorded one: ok, or the same error and reason."""
    keys = ("ok", "error", "reason")
    return all(recorded.get(k) == replayed.get(k) for k in keys)



# ---- streamed setpoints as numbers: the recorder packs them into an array (a pickle of tuples cost the loop's
# thread ~80 us a batch when the operator streams four points every tick) and the writer makes their JSON
SETPOINT_POINTS = ("rhand", "lhand", "head", "waist", "walk", "rfoot", "lfoot")  # controller.operation.points.POINTS
#: SetpointAck.ignored (append only: recorded by index)
IGNORED = (None, "hard_stop", "before_release", "invalid", "state")
PHASES = ("boundary", "hook")
#: one row per setpoint: `order` numbers the recorder's events (the setpoints of one table share it)
SETPOINT_COLUMNS = ("order", "tick", "phase", "time_s", "point", "lx", "ly", "lz", "ax", "ay", "az", "max_stride",
                    "foot_distance", "seq", "ignored")


def setpoint_row(order: int, tick: int, phase: str, time_s: float, sp, ignored: str | None) -> tuple:
    """A setpoint (app.service.setpoints.Setpoint) and its acknowledgement as a row of SETPOINT_COLUMNS."""
    nan = math.nan
    return (order, tick, PHASES.index(phase), time_s, SETPOINT_POINTS.index(sp.point), *sp.linear_m_s,
            *sp.angular_rad_s, nan if sp.max_stride_m is None else sp.max_stride_m,
            nan if sp.foot_distance_m is None else sp.foot_distance_m, sp.seq, IGNORED.index(ignored))


def setpoint_inputs(rows: np.ndarray) -> list[tuple[int, int, dict]]:
    """The /session/inputs messages of setpoint rows: (order, tick, message), one message per table."""
    out: list[tuple[int, int, dict]] = []
    current: dict | None = None
    for r in rows.tolist():
        order, tick = int(r[0]), int(r[1])
        if current is None or out[-1][0] != order:
            current = {"tick": tick, "time_s": r[3], "kind": "setpoints", "phase": PHASES[int(r[2])],
                       "name": "setpoints", "input": [], "outcome": {"ok": True, "acks": []}, "replayable": True}
            out.append((order, tick, current))
        point, seq, ignored = SETPOINT_POINTS[int(r[4])], int(r[13]), IGNORED[int(r[14])]
        current["input"].append({"$type": "Setpoint", "fields": {
            "point": point, "linear_m_s": r[5:8], "angular_rad_s": r[8:11],
            "max_stride_m": None if math.isnan(r[11]) else r[11],
            "foot_distance_m": None if math.isnan(r[12]) else r[12], "seq": seq}})
        current["outcome"]["acks"].append([point, seq, ignored])
    return out
