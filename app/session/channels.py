"""The MCAP channels of logs and sessions: one JSON schema per topic, generated from the log row's signals
(app.service.log_row.SIGNALS) and the session's own topics, and the conversion of a row to its messages and
back (what a reader needs to rebuild the row bit for bit: JSON floats are written with their shortest exact
repr)."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping

import numpy as np

from app.service.log_row import (
    FOOTSTEP,
    LEG_CODE,
    ON_CHANGE_TOPICS,
    ROW_FOOTSTEPS,
    ROW_LENGTH,
    SIGNALS,
    SLICES,
    TICK_TOPICS,
    Signal,
    signal,
)

JSON_SCHEMA = "jsonschema"  # MCAP schema encoding of a JSON schema (what Foxglove and PlotJuggler read)
SCHEMA_PREFIX = "hrp2."
_LEGS = {v: k for k, v in LEG_CODE.items()}
_FOOTSTEPS_TOPIC = "/footsteps"
TF_TOPIC = "/tf"  # BODY in the world as simulated: Foxglove's 3D panel draws it (foxglove.FrameTransform)

#: the session's own topics (not from the row): schema name -> (topic, JSON schema of the message)
INPUTS_TOPIC = "/session/inputs"
PARAMS_TOPIC = "/session/params"
BEHAVIORS_TOPIC = "/session/behaviors"
DIGEST_TOPIC = "/session/sim_digest"
SESSION_METADATA = "hrp2.session"  # MCAP metadata record of a session's header
LOG_METADATA = "hrp2.log"  # of a DataLogger export

_TICK_FIELDS = {
    "tick": {"type": "integer", "description": "tick of the log (session: counted from its start)"},
    "time_s": {"type": "number", "description": "simulated time of the controller [s] (restarts at a reset)"},
}


def _value_schema(s: Signal) -> dict:
    scalar = {"type": "boolean"} if s.kind == "bool" else {"type": ["number", "null"]}
    if not s.names:
        return {**scalar, "description": f"{s.description} [{s.unit}]"}
    return {"type": ["object", "null"], "description": f"{s.description} [{s.unit}]",
            "properties": {n: dict(scalar) for n in s.names}}


def _nest(properties: dict, key: str, schema: dict) -> None:
    head, _, rest = key.partition(".")
    if not rest:
        properties[head] = schema
        return
    node = properties.setdefault(head, {"type": "object", "properties": {}})
    _nest(node["properties"], rest, schema)


def row_topic_schemas() -> dict[str, dict]:
    """Topic -> JSON schema of its message, for the row's topics."""
    out: dict[str, dict] = {}
    for s in SIGNALS:
        if s.topic == _FOOTSTEPS_TOPIC:
            continue
        schema = out.setdefault(s.topic, {"type": "object", "properties": dict(_TICK_FIELDS)})
        _nest(schema["properties"], s.key, _value_schema(s))
    out[_FOOTSTEPS_TOPIC] = {"type": "object", "properties": {**_TICK_FIELDS, "footsteps": {
        "type": "array", "description": f"the next (up to {ROW_FOOTSTEPS}) footsteps not landed yet, world [m, rad]",
        "items": {"type": "object", "properties": {"leg": {"type": "string", "enum": list(LEG_CODE)},
                                                   **{k: {"type": "number"} for k in FOOTSTEP[1:]}}}}}}
    out[TF_TOPIC] = {"title": "foxglove.FrameTransform", "type": "object", "properties": {
        "timestamp": {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}},
        "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
        "translation": {"type": "object", "properties": {k: {"type": "number"} for k in "xyz"}},
        "rotation": {"type": "object", "properties": {k: {"type": "number"} for k in "xyzw"}}}}
    return out


SESSION_SCHEMAS: dict[str, dict] = {
    INPUTS_TOPIC: {"type": "object", "description": "an input applied at a tick boundary, as recorded", "properties": {
        "tick": {"type": "integer", "description": "the session tick it took effect before"},
        "time_s": {"type": "number", "description": "control time of that boundary [s]"},
        "kind": {"type": "string", "enum": ["verb", "estop", "setpoints", "capture"],
                 "description": "capture: a camera capture's result was not ready when due (result_late) or entered "
                                "at this boundary after that (result_entered); input: the capture's number"},
        "phase": {"type": "string", "enum": ["boundary", "hook"],
                  "description": "boundary: between ticks (verbs, e-stop); hook: the streamed setpoints taken at "
                                 "the start of the tick"},
        "name": {"type": "string", "description": "the verb's name, 'estop', 'setpoints', 'result_late' or "
                                                  "'result_entered'"},
        "input": {"description": "the verb's fields (tagged JSON: app.session.inputs) or the setpoints"},
        "outcome": {"type": "object", "description": "ok, or the error (kind, reason, message); setpoint acks"},
        "replayable": {"type": "boolean"}}},
    PARAMS_TOPIC: {"type": "object", "description": "a parameter change that took effect", "properties": {
        "tick": {"type": "integer"}, "time_s": {"type": "number"},
        "changes": {"type": "object", "description": "{owner: {field: value}}"}}},
    BEHAVIORS_TOPIC: {"type": "object", "description": "the behaviour runs, after one started or ended", "properties": {
        "tick": {"type": "integer"}, "time_s": {"type": "number"},
        "runs": {"type": "array", "items": {"type": "object"}}}},
    DIGEST_TOPIC: {"type": "object", "description": "a digest of the simulator's whole configuration (qpos) after "
                                                    "the tick: the replay compares it", "properties": {
        "tick": {"type": "integer"}, "time_s": {"type": "number"},
        "qpos_blake2b": {"type": "string"}, "nq": {"type": "integer"}}},
}


def schema_name(topic: str) -> str:
    if topic == TF_TOPIC:
        return "foxglove.FrameTransform"
    return SCHEMA_PREFIX + topic.strip("/").replace("/", ".")


def dumps(message: Mapping) -> bytes:
    """A message as compact JSON (floats written exactly; NaN is never written: it is null)."""
    return json.dumps(message, separators=(",", ":"), allow_nan=False).encode()


# ---- a row to its messages -----------------------------------------------------------------------------------
# The writer makes ~9 messages a tick: built as text from the row's values (each float its shortest exact repr,
# as json.dumps writes it) instead of dicts through json.dumps: the session writer's CPU per tick 0.32 -> 0.21 ms
# (the rest is mcap's own per-message work).
def _num(v: float) -> str:
    """A float as JSON, exactly: NaN is null; infinities are 1e999 / -1e999 (read back as infinities)."""
    if v != v:
        return "null"
    if v in (math.inf, -math.inf):
        return "1e999" if v > 0 else "-1e999"
    return repr(v)


def _signal_writer(s: Signal):
    """values (its columns, floats) -> the signal's JSON value."""
    if s.kind == "bool":
        return lambda values: "true" if values[0] > 0.5 else "false"
    if not s.names:
        return lambda values: _num(values[0])
    keys = [json.dumps(n) + ":" for n in s.names]

    def write(values) -> str:
        if all(v != v for v in values):
            return "null"
        return "{" + ",".join(k + _num(v) for k, v in zip(keys, values, strict=True)) + "}"

    return write


def _topic_writer(topic: str):
    """(head text, row values) -> the topic's message as JSON text; nested keys ("act.rfsensor") as objects."""
    tree: dict = {}
    for s, sl in _BY_TOPIC[topic]:
        node = tree
        *parents, last = s.key.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = (_signal_writer(s), sl)

    def render(node, values) -> str:
        parts = []
        for key, child in node.items():
            text = "{" + render(child, values) + "}" if isinstance(child, dict) else child[0](values[child[1]])
            parts.append(json.dumps(key) + ":" + text)
        return ",".join(parts)

    return lambda head, values: "{" + head + "," + render(tree, values) + "}"


_BY_TOPIC: dict[str, list[tuple[Signal, slice]]] = {}
for _s in SIGNALS:
    _BY_TOPIC.setdefault(_s.topic, []).append((_s, SLICES[_s]))
_TOPIC_SPANS = {t: slice(sigs[0][1].start, sigs[-1][1].stop) for t, sigs in _BY_TOPIC.items()}
_WRITERS = {t: _topic_writer(t) for t in _BY_TOPIC if t != _FOOTSTEPS_TOPIC}


def row_payloads(tick: int, row: np.ndarray, previous: np.ndarray | None) -> list[tuple[str, bytes]]:
    """The messages of one row as JSON bytes: every tick topic, and the on-change topics when their columns
    differ from `previous` (None: the first row, all of them)."""
    values = row.tolist()
    head = f'"tick":{int(tick)},"time_s":{_num(values[0])}'
    out = []
    for topic in (*TICK_TOPICS, *ON_CHANGE_TOPICS):
        span = _TOPIC_SPANS[topic]
        if topic in ON_CHANGE_TOPICS and previous is not None and _same(row[span], previous[span]):
            continue
        if topic == _FOOTSTEPS_TOPIC:
            text = "{" + head + ',"footsteps":' + json.dumps(_footsteps(values[span]), allow_nan=False) + "}"
        else:
            text = _WRITERS[topic](head, values)
        out.append((topic, text.encode()))
    return out


def row_messages(tick: int, row: np.ndarray, previous: np.ndarray | None) -> list[tuple[str, dict]]:
    """row_payloads as dicts (what a reader gets)."""
    return [(topic, json.loads(data)) for topic, data in row_payloads(tick, row, previous)]


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.tobytes() == b.tobytes()


def _footsteps(values: list[float]) -> list[dict]:
    n = len(FOOTSTEP)
    out = []
    for i in range(ROW_FOOTSTEPS):
        leg, *rest = values[i * n:(i + 1) * n]
        if leg not in _LEGS:  # NaN: no more footsteps (a row the filler made has no other value)
            break
        out.append({"leg": _LEGS[leg], **dict(zip(FOOTSTEP[1:], rest, strict=True))})
    return out


_SIM_POS = SLICES[signal("/base", "pos_sim_m")]
_SIM_QUAT = SLICES[signal("/base", "quat_sim")]


def tf_payload(row: np.ndarray, time_ns: int) -> bytes:
    """foxglove.FrameTransform of BODY in the world as simulated, as JSON bytes."""
    x, y, z = (_num(v) for v in row[_SIM_POS].tolist())
    qw, qx, qy, qz = (_num(v) for v in row[_SIM_QUAT].tolist())
    return (f'{{"timestamp":{{"sec":{time_ns // 1_000_000_000},"nsec":{time_ns % 1_000_000_000}}},'
            f'"parent_frame_id":"world","child_frame_id":"BODY","translation":{{"x":{x},"y":{y},"z":{z}}},'
            f'"rotation":{{"x":{qx},"y":{qy},"z":{qz},"w":{qw}}}}}').encode()


# ---- messages back to a row ----------------------------------------------------------------------------------
def _get(message: Mapping, key: str):
    for part in key.split("."):
        if not isinstance(message, Mapping):
            return None
        message = message.get(part)
    return message


def fill_from_message(row: np.ndarray, topic: str, message: Mapping) -> None:
    """Write a row topic's message into `row` (the inverse of row_messages for that topic)."""
    if topic == _FOOTSTEPS_TOPIC:
        n = len(FOOTSTEP)
        cols = np.full(ROW_FOOTSTEPS * n, math.nan)
        for i, step in enumerate(message.get("footsteps", ())[:ROW_FOOTSTEPS]):
            cols[i * n:(i + 1) * n] = (LEG_CODE[step["leg"]], *(step[k] for k in FOOTSTEP[1:]))
        row[_TOPIC_SPANS[topic]] = cols
        return
    for s, sl in _BY_TOPIC[topic]:
        value = _get(message, s.key)
        if s.kind == "bool":
            row[sl] = 1.0 if value else 0.0
        elif value is None:
            row[sl] = math.nan
        elif not s.names:
            row[sl] = float(value)
        else:
            row[sl] = [math.nan if value.get(n) is None else float(value[n]) for n in s.names]


ROW_TOPICS = (*TICK_TOPICS, *ON_CHANGE_TOPICS)
assert sum(sl.stop - sl.start for sl in _TOPIC_SPANS.values()) == ROW_LENGTH - 1  # every column on a topic
