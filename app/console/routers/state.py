"""Read-only endpoints: the latest state (schema generated from the layers' status), the loop's timing, the
robot process's health, the console configuration, the data log."""

from __future__ import annotations

import csv
import io
from typing import Annotated

from fastapi import APIRouter, Query
from fastapi.responses import PlainTextResponse, Response

from app.console.deps import JournalDep, LockDep, ServiceDep, SettingsDep
from app.console.errors import errors
from app.console.schemas import ConsoleConfig, Health, LoopTimingResponse, RunCounters
from app.console.state import state_model, with_console_state
from app.service.data_logger import csv_header

router = APIRouter(prefix="/api", tags=["state"])

StateDocument = state_model()


@router.get("/state", summary="Latest snapshot: time, base, joints, COG/ZMP, every stop, each layer's status",
            response_model=StateDocument, responses=errors())
async def get_state(service: ServiceDep, lock: LockDep, journal: JournalDep) -> Response:
    # (app.console.hot_paths answers this path before FastAPI does; this route documents it and answers its errors)
    # the document is built and encoded once per snapshot (0.6 ms, 50 times a second at most)
    return Response(content=with_console_state(service.state_json(), lock, journal), media_type="application/json")


@router.get("/loop/timing", response_model=LoopTimingResponse, responses=errors(),
            summary="How the control loop keeps its deadlines: tick start-lateness p50/p99/max [ms] over the "
                    "last ticks, simulated / wall time of the last 1-s windows")
def loop_timing(service: ServiceDep,
                last_s: Annotated[float | None, Query(ge=0.005, le=3600.0, description="only the ticks of the "
                                                      "last seconds (default: all kept, up to 60 s)")] = None
                ) -> LoopTimingResponse:
    return LoopTimingResponse(**service.timing(last_s).to_dict())


@router.get("/health", response_model=Health, summary="Whether the robot process runs, and why not")
def health(service: ServiceDep) -> Health:
    robot = service.robot
    alive = robot.alive
    pub = robot.latest() if alive else None
    return Health(robot_alive=alive, exit_reason=None if alive else robot.exit_reason, priority=robot.priority,
                  scene=service.info.scene, run=None if pub is None else RunCounters(**pub.stats))


@router.get("/config", response_model=ConsoleConfig, summary="What the operator page needs to know")
def get_config(service: ServiceDep, settings: SettingsDep) -> ConsoleConfig:
    import math

    info = service.info
    return ConsoleConfig(
        viewer_port=settings.viewer_port, estop_port=getattr(service.robot, "estop_door_port", None),
        joints=list(info.joint_names),
        joint_limits_deg={n: [round(math.degrees(lo), 3), round(math.degrees(hi), 3)]
                          for n, lo, hi in zip(info.joint_names, info.q_lower_rad, info.q_upper_rad, strict=True)},
        scenes=list(info.scenes))


@router.get("/log.csv", response_class=PlainTextResponse, summary="DataLogger ring buffer as CSV",
            responses={**errors(), 200: {"content": {"text/csv": {}}, "description": "the CSV"}})
def get_log_csv(service: ServiceDep) -> PlainTextResponse:
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(csv_header())
    for row in service.log_rows().tolist():
        w.writerow([f"{v:.6g}" for v in row])
    return Response(out.getvalue(), media_type="text/csv; charset=utf-8",
                             headers={"Content-Disposition": 'attachment; filename="hrp2_log.csv"'})



@router.get("/log.mcap", summary="DataLogger ring buffer as MCAP (Foxglove, PlotJuggler): JSON channels with "
                                 "their schemas, stamped with the control time",
            responses={**errors(), 200: {"content": {"application/octet-stream": {}}, "description": "the MCAP"}})
def get_log_mcap(service: ServiceDep) -> Response:
    from app.session.mcap_log import rows_to_mcap

    rows = service.log_rows()
    dt = service.info.dt_control_s
    out = io.BytesIO()
    rows_to_mcap(rows, out, [round(t / dt) for t in rows[:, 0].tolist()], {"source": "DataLogger",
                                                                          "scene": service.info.scene})
    return Response(out.getvalue(), media_type="application/octet-stream",
                    headers={"Content-Disposition": 'attachment; filename="hrp2_log.mcap"'})
