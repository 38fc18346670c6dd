"""Read-only endpoints: the latest state, the console configuration, the data log."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from fastapi.responses import PlainTextResponse

from app.deps import RuntimeDep, SettingsDep
from app.schemas import ConsoleConfig
from robot.names import JOINT_NAMES

router = APIRouter(prefix="/api", tags=["state"])


@router.get("/state", summary="Latest snapshot: time, base, joints, COG/ZMP, emergency, layers")
def get_state(runtime: RuntimeDep) -> dict[str, Any]:
    return runtime.state()


@router.get("/config", response_model=ConsoleConfig, summary="What the operator page needs to know")
def get_config(runtime: RuntimeDep,
               settings: SettingsDep) -> ConsoleConfig:
    return ConsoleConfig(
        viewer_port=settings.viewer_port,
        joints=list(JOINT_NAMES),
        joint_limits_deg={n: [round(v, 3) for v in runtime.joint_limits_deg(n)] for n in JOINT_NAMES},
        scenes=runtime.available_scenes(),
    )


@router.get("/log.csv", response_class=PlainTextResponse, summary="DataLogger ring buffer as CSV")
def get_log_csv(runtime: RuntimeDep) -> PlainTextResponse:
    return PlainTextResponse(runtime.logger.to_csv(), media_type="text/csv",
                             headers={"Content-Disposition": 'attachment; filename="hrp2_log.csv"'})
