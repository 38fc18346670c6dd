"""HTTP error mapping: every rejection says which field was wrong and what would have been allowed."""

from __future__ import annotations

import logging
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

from controller.errors import InvalidCommand, InvalidState

log = logging.getLogger(__name__)


class BadRequest(Exception):
    """A request rejected by the app's own checks (before anything reaches the loop) -> 422."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}")
        self.field = field
        self.message = message


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
        return f"{field}: must be a finite number (got {err.get('input')!r})"
    if typ == "json_invalid":
        return f"body: invalid JSON ({err.get('ctx', {}).get('error', msg)})"
    shown = err.get("input")
    text = repr(shown)
    if len(text) > 80:
        text = text[:77] + "..."
    return f"{field}: {msg} (got {text})"


def _json_safe_errors(errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    for e in errors:
        out.append({"loc": [str(p) for p in e.get("loc", ())], "msg": str(e.get("msg", "")),
                    "type": str(e.get("type", ""))})
    return out


def _relevant(errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Drop "input should be a list" from the dict branch of a union when the other branch says more."""
    wrong_branch = [e for e in errors if str(e.get("type", "")).endswith("_type")
                    and e.get("loc") and _is_union_tag(e["loc"][-1])]
    rest = [e for e in errors if e not in wrong_branch]
    return rest or errors


async def _validation_handler(_: Request, exc: RequestValidationError) -> JSONResponse:
    errors = _relevant(list(exc.errors()))
    detail = "; ".join(_readable(e) for e in errors) or "invalid request"
    return JSONResponse(status_code=422, content={"detail": detail, "errors": _json_safe_errors(errors)})


async def _bad_request_handler(_: Request, exc: BadRequest) -> JSONResponse:
    return JSONResponse(status_code=422, content={"detail": str(exc), "field": exc.field})


async def _invalid_command_handler(_: Request, exc: InvalidCommand) -> JSONResponse:
    return JSONResponse(status_code=422, content={"detail": str(exc)})


async def _invalid_state_handler(_: Request, exc: InvalidState) -> JSONResponse:
    return JSONResponse(status_code=409, content={"detail": str(exc)})


async def _timeout_handler(_: Request, exc: FutureTimeout) -> JSONResponse:
    return JSONResponse(status_code=503, content={"detail": "the control loop did not take the command in time"})


async def _internal_handler(_: Request, exc: Exception) -> JSONResponse:
    log.exception("request failed: %s", exc)
    return JSONResponse(status_code=500, content={"detail": f"internal error: {type(exc).__name__}: {exc}"})


def install_error_handlers(app: FastAPI) -> None:
    app.add_exception_handler(RequestValidationError, _validation_handler)
    app.add_exception_handler(BadRequest, _bad_request_handler)
    app.add_exception_handler(InvalidCommand, _invalid_command_handler)
    app.add_exception_handler(InvalidState, _invalid_state_handler)
    app.add_exception_handler(FutureTimeout, _timeout_handler)
    app.add_exception_handler(Exception, _internal_handler)
