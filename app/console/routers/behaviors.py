"""Behaviours ([OP] IV, the behaviour level): the list with each one's parameters (types, units, ranges from
its own Params class), starting one (a run id), a run's state, progress and result, and cancelling it.
Each behaviour has its own POST route whose body schema is generated from its Params class.
(No `from __future__ import annotations` here: the routes' annotations are classes built at import.)"""

import dataclasses
from typing import Annotated, Any, Literal, Union

from fastapi import APIRouter, Body, Path, Query, Request
from fastapi.responses import JSONResponse
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, create_model
from starlette.exceptions import HTTPException as StarletteHTTPException

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.schemas import BehaviorDoc, Ok, RunStarted
from app.console.state import jsonable, run_model
from behaviors.base import BehaviorParams
from behaviors.registry import BEHAVIORS
from behaviors.sequence import MAX_STEPS

router = APIRouter(prefix="/api/behaviors", tags=["behaviors"])

RunStatusModel = run_model()
_RUN_ERRORS = errors(404, 409, 422, e409="refused: a running behaviour drives the same point (`detail` names "
                                         "it), the e-stop, a motion stop, a fall, or the robot's state")


class _Params(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


def _integral(value: Any) -> Any:
    """JSON Schema's "integer" includes 3.0: an integral float is taken as that integer (as the parameter PUTs
    do); 3.5, true and "3" still fail the strict int check that follows."""
    if isinstance(value, float) and value.is_integer() and abs(value) < 2**53:
        return int(value)
    return value


Integral = Annotated[int, BeforeValidator(_integral)]


def params_model(cls: type[BaseModel] | type[BehaviorParams], title: str) -> type[BaseModel]:
    """A pydantic body from a behaviour's Params dataclass: each field's type, range, choices, unit, default."""
    fields: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        meta = f.metadata
        unit = meta.get("unit")
        desc = (meta.get("doc") or f.name) + (f" [{unit}]" if unit and unit != "-" else "")
        kind = type(f.default)
        if meta.get("choices") is not None:
            tp: Any = Literal[tuple(meta["choices"])]
            fields[f.name] = (tp, Field(default=f.default, description=desc))
        elif kind in (int, float):
            fields[f.name] = (Integral if kind is int else float,
                              Field(default=f.default, ge=meta.get("min"), le=meta.get("max"), description=desc))
        elif kind is bool:
            fields[f.name] = (bool, Field(default=f.default, description=desc))
        elif f.name == "steps":
            fields[f.name] = (list[_step_model()], Field(min_length=1, max_length=MAX_STEPS, description=desc))
        else:
            fields[f.name] = (kind, Field(default=f.default, description=desc))
    return create_model(title, __base__=_Params, **fields)


_STEP: list[Any] = []


def _step_model() -> Any:
    """One step of a sequence: {"behavior": name, "params": {...}}, a union tagged by the name."""
    if not _STEP:
        models = []
        for name, cls in sorted(BEHAVIORS.items()):
            if name == "sequence":
                continue
            body = params_model(cls.Params, f"{cls.Params.__name__}Body")
            models.append(create_model(f"{cls.__name__}Step", __base__=_Params,
                                       behavior=(Literal[name], Field(description="the behaviour")),
                                       params=(body, Field(default_factory=body, description="its parameters"))))
        _STEP.append(Annotated[Union[tuple(models)], Field(discriminator="behavior")])  # noqa: UP007
    return _STEP[0]


@router.get("", response_model=list[BehaviorDoc], responses=errors(),
            summary="Every behaviour, with its parameters: type, unit, range, choices, default")
def list_behaviors(service: ServiceDep) -> list[dict[str, Any]]:
    return jsonable(service.list_behaviors())


Mode = Annotated[Literal["run", "step"], Query(description="run: without pauses (the default); step: the run "
                                                            "holds before each of its phases until POST "
                                                            "/api/behaviors/runs/{id}/step (the first runs at once)")]


class PlannedStepDoc(BaseModel):
    side: Literal["right", "left"]
    x_m: float = Field(description="sole frame origin, world x [m] (leg odometry)")
    y_m: float = Field(description="world y [m]")
    yaw_rad: float = Field(description="heading, world yaw [rad]")
    phase: str = Field(description="the phase of the plan it belongs to")


class PathDoc(BaseModel):
    phase: str
    hand: str = Field(description="the operational point: rhand, lhand, waist")
    points_m: list[list[float]] = Field(description="its straight line, world (x, y, z) [m]")


class BehaviorPreview(BaseModel):
    behavior: str
    footsteps: list[PlannedStepDoc] = Field(description="planned footsteps, the first the current support foot")
    hand_paths: list[PathDoc]
    phases: list[dict[str, str]] = Field(description="the plan's phases in order: {phase, behavior}")
    complete: bool = Field(description="false: the preview ends before the plan's end (`ends` says why)")
    ends: str


def _values(name: str, params: BaseModel | None) -> dict[str, Any]:
    values = {} if params is None else params.model_dump(exclude_unset=True)
    if name == "sequence":
        values = {"steps": [{"behavior": s["behavior"], "params": s.get("params", {})} for s in values["steps"]]}
    return values


def _add_run_route(name: str) -> None:
    cls = BEHAVIORS[name]
    model = params_model(cls.Params, f"{cls.Params.__name__}Body")
    required = name == "sequence"

    def start(service: ServiceDep, params: Annotated[model | None, Body()] = None,  # type: ignore
              mode: Mode = "run") -> RunStarted:
        run_id = service.run_behavior(name, _values(name, params), mode)
        return RunStarted(id=run_id, message=f"{name} started (run {run_id}{', step mode' if mode == 'step' else ''})")

    def preview(service: ServiceDep, params: Annotated[model | None, Body()] = None) -> dict:  # type: ignore
        return jsonable(service.preview_behavior(name, _values(name, params)))

    if required:
        def start_sequence(service: ServiceDep, params: Annotated[model, Body()],  # type: ignore
                           mode: Mode = "run") -> RunStarted:
            return start(service, params, mode)

        def preview_sequence(service: ServiceDep, params: Annotated[model, Body()]) -> dict:  # type: ignore
            return preview(service, params)
        endpoint, preview_endpoint = start_sequence, preview_sequence
    else:
        endpoint, preview_endpoint = start, preview
    router.add_api_route(f"/{name}", endpoint, methods=["POST"], response_model=RunStarted, responses=_RUN_ERRORS,
                         summary=f"Start `{name}`: {cls.summary} (body: its parameters; omitted: defaults)",
                         name=f"run_{name}")
    router.add_api_route(f"/{name}/preview", preview_endpoint, methods=["POST"], response_model=BehaviorPreview,
                         responses=errors(404, 409, 422),
                         summary=f"Preview `{name}`: its planned footsteps and hand paths from its own plan, drawn "
                                 "in the 3D view as a ghost; nothing moves", name=f"preview_{name}")


for _name in sorted(BEHAVIORS):
    _add_run_route(_name)


async def unknown_behavior_handler(request: Request, exc: StarletteHTTPException) -> JSONResponse:
    """FastAPI's 404 for a path no route has; under POST /api/behaviors/ it lists the valid behaviours (a
    catch-all route would overlap /api/behaviors/runs)."""
    detail = exc.detail
    path = request.url.path
    if exc.status_code == 404 and request.method == "POST" and path.startswith("/api/behaviors/"):
        name = path.removeprefix("/api/behaviors/").removesuffix("/preview")
        detail = f"unknown behaviour {name!r}; valid: {', '.join(sorted(BEHAVIORS))}"
    return JSONResponse({"detail": detail}, status_code=exc.status_code, headers=getattr(exc, "headers", None))


RunId = Annotated[int, Path(ge=1, le=2**31, description="a run id (POST /api/behaviors/{name} gives it)")]


@router.get("/runs", response_model=list[RunStatusModel], responses=errors(),
            summary="The runs kept (the running ones and the last finished), oldest first")
def list_runs(service: ServiceDep) -> list[dict[str, Any]]:
    return jsonable([r.to_dict() for r in service.runs()])


@router.get("/runs/{run_id}", response_model=RunStatusModel, responses=errors(404),
            summary="One run: state (running, succeeded, failed, cancelled), progress 0..1, message, result")
def get_run(run_id: RunId, service: ServiceDep) -> dict[str, Any]:
    return jsonable(service.get_run(run_id).to_dict())


@router.post("/runs/{run_id}/step", response_model=RunStatusModel,
             responses=errors(404, 409, e409="the run has ended, or runs without pauses (mode 'run')"),
             summary="Step mode: let a run start its next phase; it holds again before the one after")
def step_run(run_id: RunId, service: ServiceDep) -> dict[str, Any]:
    return jsonable(service.step_run(run_id).to_dict())


@router.delete("/preview", response_model=Ok, responses=errors(),
               summary="Clear the preview's ghost from the 3D view")
def clear_preview(service: ServiceDep) -> Ok:
    service.clear_preview()
    return Ok(message="preview cleared")


@router.post("/runs/{run_id}/cancel", response_model=RunStatusModel, responses=errors(404),
             summary="Cancel a run: it stops and leaves zero velocity behind (a finished run is returned as is)")
def cancel_run(run_id: RunId, service: ServiceDep) -> dict[str, Any]:
    return jsonable(service.cancel_run(run_id).to_dict())
