"""The operator's hard e-stop: engage and release (hrpsys HardEmergencyStopper service)."""

from __future__ import annotations

from fastapi import APIRouter

from app.deps import RuntimeDep
from app.schemas import Ok

router = APIRouter(prefix="/api/estop", tags=["emergency"])


@router.post("", response_model=Ok, summary="Engage the hard e-stop: freeze the joint command now")
def engage(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    runtime.call(lambda: loop.chain["hes"].engage())
    return Ok(message="hard e-stop engaged")


@router.post("/release", response_model=Ok,
             summary="Release the hard e-stop (blends back to the live command) and clear the fault",
             responses={409: {"description": "the hard e-stop is not engaged"}})
def release(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop

    def _release() -> None:
        loop.chain["hes"].release()  # InvalidState (-> 409) when not engaged
        loop.clear_fault()

    runtime.call(_release)
    return Ok(message="hard e-stop released")
