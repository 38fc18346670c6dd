"""Every layer's parameters as one document: dump them, or load such a document (all or none). The values
and the schema (unit, default, range, choices) come from each layer's Params dataclass through
app.console.params_http, so a new parameter appears here without code."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Body

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.params_http import params_changes_schema
from app.console.state import jsonable
from app.service import InvalidArgument
from controller.core.layer import Params

router = APIRouter(prefix="/api", tags=["layers"])


@router.get("/params", responses=errors(),
            summary="Every layer's parameters as one JSON document {owner: {field: value}} (a dump to load back "
                    "with PUT, or to start the console with `--params FILE`); owners are layer names and "
                    "'ic:<limb>' for a hand's impedance")
def get_all_params(service: ServiceDep) -> dict[str, dict[str, Any]]:
    return jsonable({owner: p.to_dict() for owner, p in service.params().items()})


def _all_owners() -> dict[str, type[Params]]:
    """Every parameter owner of the chain this console builds, and its Params class."""
    from controller.layers.impedance_controller import LIMBS, ImpedanceParams
    from controller.system import layer_params_classes

    return {**layer_params_classes(), **{f"ic:{limb}": ImpedanceParams for limb in LIMBS}}


def _document_schema() -> dict[str, Any]:
    owners = _all_owners()
    return {"requestBody": {"required": True, "content": {"application/json": {"schema": {
        "title": "ParamsDocument", "type": "object", "minProperties": 1, "additionalProperties": False,
        "properties": {owner: params_changes_schema(cls) for owner, cls in owners.items()}}}}}}


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
