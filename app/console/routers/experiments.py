"""The emergency-stop experiments of [MLC] IV-C over HTTP: list them, run one in a fresh simulation, fetch
its CSV and PNG.

A run builds its own plant and controller in a process of its own (one per run: nothing of it stays in
the console, and the live robot process is never touched). One run at a time (409 otherwise). The last
results are kept in memory, their files downloadable by run id."""

from __future__ import annotations

import itertools
import multiprocessing
import threading
from collections import OrderedDict
from concurrent.futures import ProcessPoolExecutor
from typing import Annotated, Any

from fastapi import APIRouter, Body, Path, Request
from fastapi.responses import Response
from pydantic import Field, WithJsonSchema

from app.console.errors import errors
from app.console.params_http import ES_DEPRECATED, ES_PARAMS, es_changes, es_changes_schema
from app.console.schemas import ExperimentInfo, ExperimentList, ExperimentRequest, ExperimentResponse
from app.console.state import jsonable
from app.lab import experiments
from app.service import InvalidArgument, NotFound, Refused
from app.service.verbs import typed_changes
from controller.layers.emergency_stopper import EmergencyStopperParams
from controller.layers.stabilizer import StabilizerParams

router = APIRouter(prefix="/api/experiments", tags=["experiments"])

KEEP_RESULTS = 16  # runs whose files stay downloadable
_MEDIA = {"csv": "text/csv", "png": "image/png"}

#: the params a fresh simulation starts from (ControllerSystem builds its layers with the defaults)
_FRESH_PARAMS = {"es": EmergencyStopperParams(), "st": StabilizerParams()}


class ExperimentRunRequest(ExperimentRequest):
    # the schema of `params` is the EmergencyStopper PUT's (names, types, ranges); the values are checked as
    # there, with the field named `params.<name>` in a 422
    params: Annotated[dict[str, Any], WithJsonSchema(es_changes_schema())] | None = Field(
        default=None, description="EmergencyStopper parameters for this run only, named and bounded as in "
                                  "PUT /api/emergency-stopper/params; the others keep their defaults",
        examples=[{"cp_threshold_m": 0.03}])


class ExperimentRunner:
    """Runs one experiment at a time, each in a new spawned process; keeps the last results."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._ids = itertools.count(1)
        self.results: OrderedDict[int, dict] = OrderedDict()
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"),
                                             max_tasks_per_child=1)
        return self._pool

    def run(self, name: str, es: bool, variant: str | None, params: dict, save: bool,
            duration_s: float | None = None) -> tuple[int, dict]:
        from app.lab.experiments.worker import run_in_worker

        if not self._lock.acquire(blocking=False):
            raise Refused("state", "another experiment is running; try again when it has finished")
        try:
            out = self._executor().submit(run_in_worker, name, es, variant, params, save, duration_s).result()
        finally:
            self._lock.release()
        run_id = next(self._ids)
        self.results[run_id] = out.pop("files")
        while len(self.results) > KEEP_RESULTS:
            self.results.popitem(last=False)
        return run_id, out

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None


def _runner(request: Request) -> ExperimentRunner:
    runner = getattr(request.app.state, "experiments", None)
    if runner is None:
        runner = request.app.state.experiments = ExperimentRunner()
    return runner


def _info(name: str, exp) -> ExperimentInfo:
    return ExperimentInfo(name=name, description=" ".join((exp.description or "").split()), scene=exp.scene,
                          duration_s=float(exp.duration_s), variants=list(exp.variants),
                          impedance=list(exp.impedance))


@router.get("", response_model=ExperimentList, summary="The experiments: name, description, scene, variants")
def list_experiments() -> ExperimentList:
    return ExperimentList(experiments=[_info(n, e) for n, e in experiments.EXPERIMENTS.items()])


@router.post("/{name}", response_model=ExperimentResponse, responses=errors(404, 409, 422),
             summary="Run an experiment in a fresh simulation (its own process, not the live robot) and return "
                     "its verdict and figures; with `save`, its CSV and PNG are downloadable by run id")
def run(name: Annotated[str, Path(description="experiment name (GET /api/experiments)", max_length=64)],
        request: Request, req: Annotated[ExperimentRunRequest | None, Body()] = None) -> ExperimentResponse:
    req = req or ExperimentRunRequest()
    table = experiments.EXPERIMENTS
    if name not in table:
        raise NotFound(f"unknown experiment {name!r}; available: {', '.join(table)}")
    variants = table[name].variants
    if req.variant is not None and req.variant not in variants:
        raise InvalidArgument("variant", f"unknown variant {req.variant!r} of {name}; available: {', '.join(variants)}")
    grouped = {}
    if req.params is not None:
        if not req.params:
            raise InvalidArgument("params", f"give at least one parameter, or leave `params` out; valid: "
                                            f"{list(ES_PARAMS)}")
        try:
            by_layer = es_changes(req.params)
        except InvalidArgument as exc:
            raise InvalidArgument("params." + exc.field, exc.message) from None
        presented = {field: n for n, (_, field) in ES_PARAMS.items()}
        try:
            grouped = {layer: typed_changes(_FRESH_PARAMS[layer], fields) for layer, fields in by_layer.items()}
        except InvalidArgument as exc:
            raise InvalidArgument("params." + presented.get(exc.field, exc.field), exc.message) from None
    run_id, out = _runner(request).run(name, req.es, req.variant, grouped, req.save, req.duration_s)
    owners = {layer: p.replaced(**grouped.get(layer, {})) for layer, p in _FRESH_PARAMS.items()}
    params = {n: getattr(owners[layer], field) for n, (layer, field) in ES_PARAMS.items()}
    params.update({old: params[name] for old, name in ES_DEPRECATED.items()})
    files = _runner(request).results.get(run_id, {})
    return ExperimentResponse(**{**jsonable(out), "params": jsonable(params), "run_id": run_id,
                                 "csv_url": f"/api/experiments/runs/{run_id}/csv" if "csv" in files else None,
                                 "png_url": f"/api/experiments/runs/{run_id}/png" if "png" in files else None})


@router.get("/runs/{run_id}/{kind}", responses={**errors(404), 200: {"content": {"text/csv": {}, "image/png": {}}}},
            response_class=Response, summary="A saved run's CSV or PNG (the last runs are kept in memory)")
def run_file(run_id: int, kind: Annotated[str, Path(json_schema_extra={"enum": list(_MEDIA)})],
             request: Request) -> Response:
    files = _runner(request).results.get(run_id)
    if files is None or kind not in files:
        kept = list(_runner(request).results)
        raise NotFound(f"no {kind!r} of run {run_id}; runs kept: {kept} (only runs with save=true have files)")
    return Response(content=files[kind], media_type=_MEDIA[kind],
                    headers={"Content-Disposition": f'attachment; filename="experiment-{run_id}.{kind}"'})
