"""FastAPI dependencies: the operator service and the settings, overridable in tests."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from app.console.command_journal import CommandJournal
from app.console.operator_lock import OperatorLock
from app.console.settings import Settings
from app.service import OperatorService, Unavailable


def get_service(request: Request) -> OperatorService:
    service = getattr(request.app.state, "service", None)
    if service is None:
        raise Unavailable("the operator service is not running")
    return service


def get_settings(request: Request) -> Settings:
    return getattr(request.app.state, "settings", None) or Settings()


def get_lock(request: Request) -> OperatorLock:
    lock = getattr(request.app.state, "lock", None)
    if lock is None:
        lock = request.app.state.lock = OperatorLock()
    return lock


def get_journal(request: Request) -> CommandJournal | None:
    """The console's journal of control requests (None when the app was built without one)."""
    return getattr(request.app.state, "journal", None)


ServiceDep = Annotated[OperatorService, Depends(get_service)]
SettingsDep = Annotated[Settings, Depends(get_settings)]
LockDep = Annotated[OperatorLock, Depends(get_lock)]
JournalDep = Annotated[CommandJournal | None, Depends(get_journal)]
