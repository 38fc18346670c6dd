"""The controller chain: its order and per-layer timing."""

from __future__ import annotations

from fastapi import APIRouter

from app.deps import RuntimeDep
from app.schemas import ChainInfo

router = APIRouter(prefix="/api", tags=["chain"])


@router.get("/chain", response_model=ChainInfo, summary="Layer order and per-layer p50/p99 tick time [ms]")
def chain(runtime: RuntimeDep) -> ChainInfo:
    loop = runtime.loop
    c = loop.chain
    return ChainInfo(order=c.order(), chain=c.describe(), timing=c.timing(),
                     tick_ms=loop.tick_timer.percentiles(), physics_ms=loop.physics_timer.percentiles())
