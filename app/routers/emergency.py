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


motion_router = APIRouter(prefix="/api/motion", tags=["emergency"])


@motion_router.post("/stop", response_model=Ok,
                    summary="Stop and revert the planned motion ([MLC] Eq. 15); balance keeps working")
def stop_motion(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    runtime.call(lambda: loop.chain["es"].stop_motion())
    return Ok(message="planned motion stopped")


@motion_router.post("/release", response_model=Ok,
                    summary="Release the motion stop: blend back to the live plan over recover_time_s",
                    responses={409: {"description": "the motion is not stopped"}})
def release_motion(runtime: RuntimeDep) -> Ok:
    loop = runtime.loop
    runtime.call(lambda: loop.chain["es"].release_motion())
    return Ok(message="motion stop released")
