"""Layer parameters as documents: current values and the schema (unit, default, range, choices) taken from
each layer's Params dataclass, so a new parameter appears here without code. Routes: every layer's
parameters at once (dump), and loading such a document (all or none)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Body

from app.deps import ServiceDep
from app.errors import errors
from app.state import jsonable
from controller.layer import Params


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


@router.put("/params", responses=errors(404, 422),
            summary="Load a parameter document {owner: {field: value}} (some owners, some fields): checked "
                    "against each Params dataclass, applied all or none at one tick boundary")
def put_all_params(service: ServiceDep,
                   document: Annotated[dict[str, dict[str, Any]], Body(description="{owner: {field: value}}")]
                   ) -> dict[str, dict[str, Any]]:
    new = service.set_params(document, prefixes={owner: f"{owner}." for owner in document})
    return jsonable({owner: p.to_dict() for owner, p in new.items()})
