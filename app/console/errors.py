"""HTTP error mapping: every rejection is a JSON body {"detail": text, ...} that says which field was wrong
and what would have been allowed; the OpenAPI schema of the 422 says the same."""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel, ConfigDict, Field

from app.console.operator_lock import Locked
from app.service.errors import InvalidArgument, PointTaken, Refused, ServiceError, Superseded
from controller.core.errors import InvalidCommand, InvalidState

log = logging.getLogger(__name__)


class ValidationItem(BaseModel):
    loc: list[str] = Field(description="where: body, then the field path")
    msg: str
    type: str


class ErrorBody(BaseModel):
    """Every error response of the API."""

    model_config = ConfigDict(extra="forbid")

    detail: str = Field(description="what was wrong and what would have worked")
    field: str | None = Field(default=None, description="the offending field (422)")
    reason: str | None = Field(default=None, description="what is in the way (409): hard_stop, fallen, collision, "
                                                         "motion_stop, walking_stop, reach, state, diverged, "
                                                         "point_taken, superseded; (423): locked")
    holder: str | None = Field(default=None, description="the display name of the operator lock's holder (423)")
    owner: str | None = Field(default=None, description="the display name of the client streaming to the point "
                                                        "(409 point_taken)")
    by: str | None = Field(default=None, description="the display name of the client whose newer setpoint the "
                                                     "robot applied instead (409 superseded)")
    errors: list[ValidationItem] | None = Field(default=None, description="pydantic's findings (422)")


def _is_union_tag(part: Any) -> bool:
    return isinstance(part, str) and "[" in part  # pydantic names union branches like "list[float]"


def _loc(loc: tuple[Any, ...]) -> str:
    parts = [str(p) for p in loc if p not in ("body", "query", "path") and not _is_union_tag(p)]
    return ".".join(parts) if parts else "body"


def _readable(err: dict[str, Any]) -> str:
    """One pydantic error as `field: what is allowed (got X)`."""
    field = _loc(tuple(err.get("loc", ())))
    msg = err.get("msg", "invalid value")
    typ = err.get("type", "")
    if typ == "missing":
        return f"{field}: field required"
    if typ == "extra_forbidden":
        return f"{field}: unknown field (not part of this request)"
    if typ == "finite_number":
        return f"{field}: must be a finite number"
    if typ == "json_invalid":
        return f"body: invalid JSON ({err.get('ctx', {}).get('error', msg)})"
    text = repr(err.get("input"))
    if len(text) > 80:
        text = text[:77] + "..."
    return f"{field}: {msg} (got {text})"


def _relevant(errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Drop "input should be a list" from the dict branch of a union when the other branch says more."""
    wrong_branch = [e for e in errors if str(e.get("type", "")).endswith("_type")
                    and e.get("loc") and _is_union_tag(e["loc"][-1])]
    rest = [e for e in errors if e not in wrong_branch]
    return rest or errors


def body(detail: str, **extra: Any) -> dict[str, Any]:
    return {"detail": detail, **{k: v for k, v in extra.items() if v is not None}}


async def _validation_handler(_: Request, exc: RequestValidationError) -> JSONResponse:
    errors = _relevant(list(exc.errors()))[:20]
    detail = "; ".join(_readable(e) for e in errors) or "invalid request"
    items = [{"loc": [str(p) for p in e.get("loc", ())], "msg": str(e.get("msg", "")), "type": str(e.get("type", ""))}
             for e in errors]
    return JSONResponse(status_code=422, content=body(detail, field=_loc(tuple(errors[0].get("loc", ())))
                                                      if errors else None, errors=items))


async def _service_handler(_: Request, exc: ServiceError) -> JSONResponse:
    extra: dict[str, Any] = {}
    if isinstance(exc, InvalidArgument):
        extra["field"] = exc.field
    if isinstance(exc, Refused):
        extra["reason"] = exc.reason
    if isinstance(exc, PointTaken):
        extra["field"] = "point"
        extra["owner"] = exc.owner
    if isinstance(exc, Superseded):
        extra["by"] = exc.by
    if exc.status >= 500:
        log.error("service error: %s", exc)
    return JSONResponse(status_code=exc.status, content=body(str(exc), **extra))


async def _invalid_command_handler(_: Request, exc: InvalidCommand) -> JSONResponse:
    return JSONResponse(status_code=422, content=body(str(exc)))


async def _invalid_state_handler(_: Request, exc: InvalidState) -> JSONResponse:
    return JSONResponse(status_code=409, content=body(str(exc), reason="state"))


async def _internal_handler(_: Request, exc: Exception) -> JSONResponse:
    # Starlette answers with this, then re-raises to the server: app.console.security.ConsoleGuard swallows that
    # re-raise, so the keep-alive connection stays usable (uvicorn would close it)
    log.error("request failed: %s: %s", type(exc).__name__, exc)
    return JSONResponse(status_code=500, content=body(f"internal error: {type(exc).__name__}: {exc}"))


async def _locked_handler(_: Request, exc: Locked) -> JSONResponse:
    return JSONResponse(status_code=423, content=body(str(exc), reason="locked", holder=exc.holder))


def install_error_handlers(app: FastAPI) -> None:
    app.add_exception_handler(Exception, _internal_handler)
    app.add_exception_handler(RequestValidationError, _validation_handler)
    app.add_exception_handler(ServiceError, _service_handler)
    app.add_exception_handler(InvalidCommand, _invalid_command_handler)
    app.add_exception_handler(InvalidState, _invalid_state_handler)
    app.add_exception_handler(Locked, _locked_handler)


#: responses every route may give besides 200 (in OpenAPI, all with the one error body)
COMMON_ERRORS = {
    401: {"model": ErrorBody, "description": "the console's token is missing or wrong (a console bound beyond "
                                             "loopback: 'Authorization: Bearer <token>')"},
    403: {"model": ErrorBody, "description": "a control request from a page of another origin"},
    405: {"model": ErrorBody, "description": "a method the path does not have (the Allow header lists those it has)"},
    413: {"model": ErrorBody, "description": "a body over 64 kB"},
    415: {"model": ErrorBody, "description": "a control request not sent as application/json"},
    421: {"model": ErrorBody, "description": "a Host header that is not the console's address"},
    500: {"model": ErrorBody, "description": "an unexpected error (the connection stays usable)"},
    503: {"model": ErrorBody, "description": "the robot process is not running or did not answer"}}
#: what control requests (POST, PUT, DELETE) may answer besides those
CONTROL_ERRORS = {423: {"model": ErrorBody, "description": "another client holds the operator lock: `holder` "
                                                           "names it; its holder sends the lease token it got "
                                                           "from POST /api/operator/lock as the X-Lock-Token "
                                                           "header (the e-stop is never refused)"}}


def errors(*codes: int, **descriptions: str) -> dict[int, dict[str, Any]]:
    """OpenAPI `responses` for a route: the error codes it may answer, each with ErrorBody."""
    default = {404: "something named does not exist (the valid names are listed)",
               409: "valid, but not now: `reason` says what is in the way (hard_stop, fallen, collision, "
                    "motion_stop, walking_stop, reach, state, diverged)",
               422: "invalid field: `field` names it, `detail` says what is allowed"}
    out = dict(COMMON_ERRORS)
    for code in codes:
        out[code] = {"model": ErrorBody, "description": descriptions.get(f"e{code}", default.get(code, ""))}
    return out
