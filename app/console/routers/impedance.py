"""Per-hand ImpedanceController (hrpsys ImpedanceControllerService): start / stop a limb and its M, D, K
parameters, with the same params document and checks as the other layers."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.params_http import ChangesBody, params_changes_body, params_document
from app.console.schemas import Ok
from app.service import NotFound
from controller.layers.impedance_controller import LIMBS, ImpedanceParams

router = APIRouter(prefix="/api/impedance", tags=["impedance"])

LimbPath = Annotated[str, Path(description=f"the hand: {' | '.join(LIMBS)}", examples=[next(iter(LIMBS))],
                               json_schema_extra={"enum": list(LIMBS)})]


def _owner(service, limb: str) -> str:
    if limb not in service.info.impedance_limbs:
        raise NotFound(f"unknown limb {limb!r}; valid limbs: {', '.join(service.info.impedance_limbs)}")
    return f"ic:{limb}"


@router.get("/{limb}/params", responses=errors(404),
            summary="Impedance parameters of one hand and their schema (unit, default, range)")
def get_params(limb: LimbPath, service: ServiceDep) -> dict[str, Any]:
    owner = _owner(service, limb)
    return params_document(service.params(owner)[owner])


@router.put("/{limb}/params", responses=errors(404, 422), openapi_extra=params_changes_body(ImpedanceParams),
            summary="Change some impedance parameters of one hand (validated, applied at a tick boundary)")
def put_params(limb: LimbPath, service: ServiceDep, changes: ChangesBody) -> dict[str, Any]:
    owner = _owner(service, limb)
    return params_document(service.set_params({owner: changes})[owner])


@router.post("/{limb}/start", response_model=Ok, responses=errors(404, 409),
             summary="Start impedance control of one hand (blends in over transition_time_s)")
def start(limb: LimbPath, service: ServiceDep) -> Ok:
    _owner(service, limb)
    return Ok(message=service.start_impedance(limb))


@router.post("/{limb}/stop", response_model=Ok, responses=errors(404, 409),
             summary="Stop impedance control of one hand (blends back to the planned pose)")
def stop(limb: LimbPath, service: ServiceDep) -> Ok:
    _owner(service, limb)
    return Ok(message=service.stop_impedance(limb))
