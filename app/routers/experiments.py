"""The emergency-stop experiments of [MLC] IV-C over HTTP: list them, run one in a fresh simulation.

A run builds its own plant and controller (never the live ones) and steps it as fast as it can in
FastAPI's threadpool (plain `def` endpoints), so the live control loop keeps its own thread. One run at a
time: a second request while one runs gets a 409."""

from __future__ import annotations

import dataclasses
import tempfile
import threading
import time
from pathlib import Path as FsPath
from typing import Annotated

from fastapi import APIRouter, Body, HTTPException, Path

from app import experiments
from app.errors import BadRequest
from app.routers.emergency import ES_PARAMS, composite_changes
from app.runtime import jsonable
from app.schemas import ExperimentInfo, ExperimentList, ExperimentRequest, ExperimentResponse
from controller.emergency_stopper import EmergencyStopperParams
from controller.stabilizer import StabilizerParams

router = APIRouter(prefix="/api/experiments", tags=["experiments"])

_running = threading.Lock()

#: the params a fresh simulation starts from (ControllerSystem builds its layers with the defaults)
_FRESH_PARAMS = {"es": EmergencyStopperParams(), "st": StabilizerParams()}


def _run_params(grouped: dict[str, dict]) -> dict:
    """The presented EmergencyStopper view of a run started from the defaults with `grouped` changes."""
    owners = {layer: p.replaced(**grouped.get(layer, {})) for layer, p in _FRESH_PARAMS.items()}
    return {name: getattr(owners[layer], param) for name, (layer, param) in ES_PARAMS.items()}


def _info(name: str, exp) -> ExperimentInfo:
    return ExperimentInfo(name=name, description=" ".join((exp.description or "").split()), scene=exp.scene,
                          duration_s=float(exp.duration_s), variants=list(exp.variants),
                          impedance=list(exp.impedance))


@router.get("", response_model=ExperimentList, summary="The experiments: name, description, scene, variants")
def list_experiments() -> ExperimentList:
    return ExperimentList(experiments=[_info(n, e) for n, e in experiments.EXPERIMENTS.items()])


@router.post("/{name}", response_model=ExperimentResponse,
             summary="Run an experiment in a fresh simulation (not the live one) and return its verdict and figures",
             responses={404: {"description": "unknown experiment (the valid names are listed)"},
                        422: {"description": "unknown variant (the valid ones are listed) or invalid body"},
                        409: {"description": "another experiment is running"}})
def run(name: Annotated[str, Path(description="experiment name (GET /api/experiments)")],
        req: Annotated[ExperimentRequest | None, Body()] = None) -> ExperimentResponse:
    req = req or ExperimentRequest()
    table = experiments.EXPERIMENTS
    if name not in table:
        raise HTTPException(status_code=404, detail=f"unknown experiment {name!r}; available: {', '.join(table)}")
    variants = table[name].variants
    if req.variant is not None and req.variant not in variants:
        raise BadRequest("variant", f"unknown variant {req.variant!r} of {name}; available: {', '.join(variants)}")
    grouped = composite_changes(_FRESH_PARAMS, ES_PARAMS, req.params, prefix="params.") if req.params else {}
    if not _running.acquire(blocking=False):
        raise HTTPException(status_code=409, detail="another experiment is running; try again when it has finished")
    try:
        out_dir = FsPath(tempfile.mkdtemp(prefix=f"hrp2-{name}-")) if req.save else None
        t0 = time.perf_counter()
        result = experiments.run_experiment(name, es=req.es, out_dir=out_dir, plot=req.save, variant=req.variant,
                                            params=grouped or None)
        wall = time.perf_counter() - t0
    finally:
        _running.release()
    return ExperimentResponse(**{**jsonable(dataclasses.asdict(result)), "params": jsonable(_run_params(grouped)),
                                 "wall_time_s": round(wall, 3)})
