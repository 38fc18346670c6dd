"""Per-hand ImpedanceController (hrpsys ImpedanceControllerService): start / stop a limb and its M, D, K
parameters, with the same params view and checks as the other layers (app.routers.layers)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path

from app.deps import RuntimeDep
from app.routers.layers import ChangesBody, check_types, params_view
from app.runtime import Runtime
from app.schemas import Ok
from controller.impedance_controller import LIMBS

router = APIRouter(prefix="/api/impedance", tags=["impedance"])

LimbPath = Annotated[str, Path(description=f"the hand: {' | '.join(LIMBS)}", examples=[next(iter(LIMBS))],
                               json_schema_extra={"enum": list(LIMBS)})]

_NOT_FOUND = {404: {"description": "unknown limb (the valid ones are listed), or no ImpedanceController"}}
_PARAM_ERRORS = {422: {"description": "unknown parameter (valid names listed), wrong type or out of range "
                                      "(the message names the field and its range)"}, **_NOT_FOUND}
_STATE_ERRORS = {409: {"description": "already active / not active"}, **_NOT_FOUND}


def _ic(runtime: Runtime, limb: str):
    """The ImpedanceController of the chain of this tick, after checking the limb against its limbs."""
    chain = runtime.loop.chain
    if "ic" not in chain:
        raise HTTPException(status_code=404, detail=f"no ImpedanceController ('ic') in the chain; "
                                                    f"present: {chain.order()}")
    ic = chain["ic"]
    if limb not in ic.limbs:
        raise HTTPException(status_code=404, detail=f"unknown limb {limb!r}; valid limbs: {', '.join(ic.limbs)}")
    return ic


@router.get("/{limb}/params", responses=_PARAM_ERRORS,
            summary="Impedance parameters of one hand and their schema (unit, default, range)")
def get_params(limb: LimbPath, runtime: RuntimeDep) -> dict[str, Any]:
    return params_view(_ic(runtime, limb).params[limb])


@router.put("/{limb}/params", responses=_PARAM_ERRORS,
            summary="Change some impedance parameters of one hand (validated, applied at a tick boundary)")
def put_params(limb: LimbPath, runtime: RuntimeDep, changes: ChangesBody) -> dict[str, Any]:
    typed = check_types(_ic(runtime, limb).params[limb], changes)

    def _apply():
        ic = _ic(runtime, limb)
        new = ic.params[limb].replaced(**typed)  # InvalidCommand (-> 422) names field and range
        ic.set_params(limb, new)
        return new

    return params_view(runtime.call(_apply))


def _add_state_route(action: str, done: str, summary: str) -> None:
    """POST /{limb}/start or /{limb}/stop: the controller's own start(limb) / stop(limb) in the loop."""

    def route(limb: LimbPath, runtime: RuntimeDep) -> Ok:
        _ic(runtime, limb)  # unknown limb: 404 before anything reaches the loop
        runtime.call(lambda: getattr(_ic(runtime, limb), action)(limb))  # InvalidState -> 409
        return Ok(message=f"impedance control of {limb} {done}")

    router.add_api_route(f"/{{limb}}/{action}", route, methods=["POST"], response_model=Ok,
                         responses=_STATE_ERRORS, summary=summary, name=f"impedance-{action}")


_add_state_route("start", "started", "Start impedance control of one hand (blends in over transition_time_s)")
_add_state_route("stop", "stopped", "Stop impedance control of one hand (blends back to the planned pose)")
