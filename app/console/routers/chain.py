"""The controller chain: its order and per-layer timing."""

from __future__ import annotations

from fastapi import APIRouter

from app.console.deps import ServiceDep
from app.console.errors import errors
from app.console.schemas import ChainInfo

router = APIRouter(prefix="/api", tags=["chain"])


@router.get("/chain", response_model=ChainInfo, responses=errors(),
            summary="Layer order and per-layer p50/p99 tick time [ms]")
def chain(service: ServiceDep) -> ChainInfo:
    return ChainInfo(**service.chain_timing())
