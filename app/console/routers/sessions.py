"""Sessions: start recording one (from a fresh simulation: the start resets it; the oldest files beyond the
retention rule are removed), stop it, list the recorded files, download one. Replay them with
`hrp2-console replay FILE` (or `--view`)."""

from __future__ import annotations

from pathlib import Path as FilePath
from typing import Annotated

from fastapi import APIRouter, Body, Path
from fastapi.responses import FileResponse
from pydantic import Field

from app.console.deps import ServiceDep, SettingsDep
from app.console.errors import errors
from app.console.schemas import StrictBody
from app.service.errors import InvalidArgument, NotFound
from app.session.files import NAME_PATTERN, BadName, checked_name, free_name, list_sessions, prune_sessions

router = APIRouter(prefix="/api/sessions", tags=["sessions"])


class StartSessionRequest(StrictBody):
    name: str | None = Field(default=None, max_length=64, pattern=NAME_PATTERN, description=(
        "the file's name in the sessions folder: letters, digits, '_', '-', '.' (no path), '.mcap' appended when "
        "missing; default session-<time>.mcap; -2, -3 ... added when it exists"), examples=["walk-test"])


def _folder(settings) -> FilePath:
    return FilePath(settings.sessions_dir).resolve()


@router.get("", summary="The session being recorded (or null) and the recorded files, newest first")
def sessions(service: ServiceDep, settings: SettingsDep) -> dict:
    return {"recording": service.recording(), "directory": str(_folder(settings)),
            "sessions": list_sessions(_folder(settings))}


@router.post("/start", responses=errors(409, 422, e409="a session is already being recorded (reason: state)"),
             summary="Reset the simulation (same scene) and record a session from its first tick: the operator's "
                     "and scripts' inputs with their ticks, behaviour runs, parameter changes, the telemetry; "
                     "`removed`: the oldest files the retention rule removed (--sessions-keep, --sessions-max-mb)")
def start(service: ServiceDep, settings: SettingsDep,
          req: Annotated[StartSessionRequest | None, Body()] = None) -> dict:
    folder = _folder(settings)
    try:
        name = free_name(folder, None if req is None else req.name)
    except BadName as exc:
        raise InvalidArgument("name", str(exc)) from None
    folder.mkdir(parents=True, exist_ok=True)
    recording = service.start_recording(str(folder / name))
    last = service.published().last_recording  # a file the writer may still be finishing
    busy = [folder / name] + ([last["path"]] if last is not None and not last["finished"] else [])
    removed = prune_sessions(folder, settings.sessions_keep, settings.sessions_max_bytes, keep=busy)
    return {"recording": recording, "removed": removed}


@router.post("/stop", responses=errors(409, e409="no session is being recorded (reason: state)"),
             summary="End the session being recorded; its status once the file is finished")
def stop(service: ServiceDep) -> dict:
    return {"recording": service.stop_recording()}


@router.get("/{name}", responses={**errors(404, 422), 200: {"content": {"application/octet-stream": {}},
                                                           "description": "the MCAP file"}},
            summary="Download a recorded session (MCAP: Foxglove and PlotJuggler open it)")
def download(name: Annotated[str, Path(max_length=64, pattern=NAME_PATTERN)], settings: SettingsDep) -> FileResponse:
    try:
        file_name = checked_name(name)
    except BadName as exc:
        raise InvalidArgument("name", str(exc)) from None
    path = _folder(settings) / file_name
    if not path.is_file():
        known = ", ".join(d["name"] for d in list_sessions(_folder(settings))[:20]) or "none yet"
        raise NotFound(f"no session {file_name!r}; recorded: {known}")
    return FileResponse(path, media_type="application/octet-stream", filename=file_name)
