"""Layer parameters as documents: current values and the schema (unit, default, range, choices) taken from
each layer's Params dataclass, so a new parameter appears here without code. Routes: every layer's
parameters at once (dump), and loading such a document (all or none)."""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any

from fastapi import APIRouter, Body

from app.deps import ServiceDep
from app.errors import errors
from app.service import InvalidArgument
from app.state import jsonable
from controller.core.layer import Params

_JSON_TYPES = {float: "number", int: "integer", bool: "boolean", str: "string"}


def field_json_schema(cls: type[Params], name: str) -> dict[str, Any]:
    """The JSON schema of one Params field: its type, range, choices, unit and default."""
    f = next(f for f in dataclasses.fields(cls) if f.name == name)
    meta = f.metadata
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


def params_changes_body(cls: type[Params]) -> dict[str, Any]:
    """OpenAPI `openapi_extra` declaring the body of a PUT of some fields of `cls`."""
    schema = changes_json_schema({f.name: (cls, f.name) for f in dataclasses.fields(cls)}, f"{cls.__name__}Changes")
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": schema}}}}


def params_document(params: Params) -> dict[str, Any]:
    """{"params": current values, "schema": [{name, default, unit, min, max, choices}...]}."""
    return jsonable({"params": params.to_dict(), "schema": type(params).describe()})


router = APIRouter(prefix="/api", tags=["layers"])


@router.get("/params", responses=errors(),
            summary="Every layer's parameters as one JSON document {owner: {field: value}} (a dump to load back "
                    "with PUT, or to start the console with `--params FILE`); owners are layer names and "
                    "'ic:<limb>' for a hand's impedance")
def get_all_params(service: ServiceDep) -> dict[str, dict[str, Any]]:
    return jsonable({owner: p.to_dict() for owner, p in service.params().items()})


def _all_owners() -> dict[str, type[Params]]:
    """Every parameter owner of the chain this console builds, and its Params class."""
    from controller.core.system import layer_params_classes
    from controller.layers.impedance_controller import LIMBS, ImpedanceParams

    return {**layer_params_classes(), **{f"ic:{limb}": ImpedanceParams for limb in LIMBS}}


def _document_schema() -> dict[str, Any]:
    owners = _all_owners()
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": {
        "title": "ParamsDocument", "type": "object", "minProperties": 1, "additionalProperties": False,
        "properties": {owner: changes_json_schema({f.name: (cls, f.name) for f in dataclasses.fields(cls)},
                                                  f"{cls.__name__}Changes")
                       for owner, cls in owners.items()}}}}}}


@router.put("/params", responses=errors(404, 422), openapi_extra=_document_schema(),
            summary="Load a parameter document {owner: {field: value}} (some owners, some fields): checked "
                    "against each Params dataclass, applied all or none at one tick boundary")
def put_all_params(service: ServiceDep,
                   document: Annotated[dict[str, dict[str, Any]], Body(description="{owner: {field: value}}")]
                   ) -> dict[str, dict[str, Any]]:
    if not document:
        raise InvalidArgument("body", f"give at least one owner; valid: {', '.join(service.info.params)}")
    new = service.set_params(document, prefixes={owner: f"{owner}." for owner in document})
    return jsonable({owner: p.to_dict() for owner, p in new.items()})
