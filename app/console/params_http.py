"""Layer parameters over HTTP, shared by the routers that read or change them: the params document (values
and the schema each Params dataclass declares), the JSON schema of a change body, and the EmergencyStopper's
parameters as one view over the layers that own them."""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any

from fastapi import Body

from app.console.state import jsonable
from app.service import InvalidArgument
from controller.core.layer import Params

_JSON_TYPES = {float: "number", int: "integer", bool: "boolean", str: "string"}


def field_json_schema(cls: type[Params], name: str) -> dict[str, Any]:
    """The JSON schema of one Params field: its type, range, choices, unit and default; a nested Params field is
    an object of some of its own fields."""
    f = next(f for f in dataclasses.fields(cls) if f.name == name)
    meta = f.metadata
    if isinstance(f.default, Params):
        inner = type(f.default)
        whole = {**params_changes_schema(inner), "description": f"{cls.__name__}.{name}: some {inner.__name__} fields"}
        switch = getattr(cls, "SWITCHES", {}).get(name)
        if switch is not None:  # a boolean is its switch alone, as parameter documents of before the nesting say
            whole = {"anyOf": [whole, {"type": "boolean", "description": f"{cls.__name__}.{name}.{switch} alone"}],
                     "description": whole["description"] + f", or true/false for {name}.{switch}"}
        return {**whole, "default": jsonable(f.default.to_dict())}
    out: dict[str, Any] = {"type": _JSON_TYPES.get(type(f.default), "string")}
    if meta.get("choices") is not None:
        out["enum"] = list(meta["choices"])
    if meta.get("min") is not None and out["type"] in ("number", "integer"):
        out["minimum"] = meta["min"]
    if meta.get("max") is not None and out["type"] in ("number", "integer"):
        out["maximum"] = meta["max"]
    unit = meta.get("unit")
    out["description"] = f"{cls.__name__}.{name}" + (f" [{unit}]" if unit and unit != "-" else "")
    out["default"] = f.default
    return out


def changes_json_schema(fields: dict[str, tuple[type[Params], str]], title: str) -> dict[str, Any]:
    """The request body of a parameter change: some of `fields` {presented name: (Params class, field)}."""
    return {"title": title, "type": "object", "minProperties": 1, "additionalProperties": False,
            "properties": {name: field_json_schema(cls, field) for name, (cls, field) in fields.items()}}


def params_changes_schema(cls: type[Params]) -> dict[str, Any]:
    """The JSON schema of some fields of `cls` (a PUT's body, an owner's part of the params document)."""
    return changes_json_schema({f.name: (cls, f.name) for f in dataclasses.fields(cls)}, f"{cls.__name__}Changes")


def params_changes_body(cls: type[Params]) -> dict[str, Any]:
    """OpenAPI `openapi_extra` declaring the body of a PUT of some fields of `cls`."""
    schema = params_changes_schema(cls)
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": schema}}}}


def params_document(params: Params) -> dict[str, Any]:
    """{"params": current values, "schema": [{name, default, unit, min, max, choices}...]}."""
    return jsonable({"params": params.to_dict(), "schema": type(params).describe()})


ChangesBody = Annotated[dict[str, Any], Body(
    description="{parameter name: new value}, e.g. {\"cp_threshold_m\": 0.05}")]


# ---- EmergencyStopper parameters: one view over the layers that own them ---------------------------------

#: presented name -> (owning chain layer, field of that layer's Params dataclass). The revert timing lives in
#: the EmergencyStopper's params, the capture-point flag that triggers it in the Stabilizer's.
ES_PARAMS: dict[str, tuple[str, str]] = {
    "t1": ("es", "t1_s"),
    "t2": ("es", "t2_s"),
    "recover_time": ("es", "recover_time_s"),
    "cp_threshold_m": ("st", "cp_threshold_m"),
    "mode": ("st", "emergency_mode"),
}
#: deprecated presented name -> the name it stands for (accepted in changes, also given in the document)
ES_DEPRECATED: dict[str, str] = {"threshold": "cp_threshold_m"}

EsChangesBody = Annotated[dict[str, Any], Body(
    description="{parameter name: new value} for some of " + ", ".join(ES_PARAMS) + ", e.g. {\"t1\": 0.8}")]


def es_changes(changes: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """{owner: {field: value}} from the presented names (unknown names -> 422 listing the valid ones)."""
    if not changes:
        raise InvalidArgument("body", f"give at least one parameter; valid: {list(ES_PARAMS)}")
    unknown = sorted(set(changes) - set(ES_PARAMS) - set(ES_DEPRECATED))
    if unknown:
        raise InvalidArgument(unknown[0], f"unknown parameter(s) {unknown}; valid: {list(ES_PARAMS)}")
    for old, name in ES_DEPRECATED.items():
        if old in changes and name in changes:  # (the schema says so too: not both)
            raise InvalidArgument(old, f"{old!r} is the deprecated name of {name!r}: give one of them")
    grouped: dict[str, dict[str, Any]] = {}
    for name, value in changes.items():
        layer, field = ES_PARAMS[ES_DEPRECATED.get(name, name)]
        grouped.setdefault(layer, {})[field] = value
    return grouped


def es_document(params: dict) -> dict[str, Any]:
    """{"params": {name: value}, "schema": [...]} in the presented names, from the owners' declarations."""
    docs = {layer: params_document(p) for layer, p in params.items()}
    values, schema = {}, []
    for name, (layer, field) in ES_PARAMS.items():
        values[name] = docs[layer]["params"][field]
        declared = next(d for d in docs[layer]["schema"] if d["name"] == field)
        schema.append({**declared, "name": name, "layer": layer, "param": f"{type(params[layer]).__name__}.{field}"})
    for old, name in ES_DEPRECATED.items():
        values[old] = values[name]
    return {"params": values, "schema": schema}


def es_changes_schema() -> dict[str, Any]:
    """The JSON schema of some EmergencyStopper parameters in the presented names (the PUT's body, and an
    experiment's `params`), from the owning layers' declarations."""
    from controller.system import layer_params_classes

    classes = layer_params_classes()
    schema = changes_json_schema({name: (classes[layer], field) for name, (layer, field) in ES_PARAMS.items()},
                                 "EmergencyStopperChanges")
    for old, name in ES_DEPRECATED.items():
        schema["properties"][old] = {**schema["properties"][name], "deprecated": True,
                                     "description": f"deprecated name of {name}"}
        schema.setdefault("allOf", []).append({"not": {"required": [old, name]}})
    return schema
