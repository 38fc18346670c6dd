"""Console settings: one frozen dataclass filled by the CLI and injected into the app."""

from __future__ import annotations

from dataclasses import dataclass

from app.session.files import KEEP_BYTES, KEEP_COUNT


@dataclass(frozen=True)
class Settings:
    scene: str = "default"
    speed: float | None = 1.0  # 1.0 = real time, None = as fast as possible
    dt_control_s: float = 0.005  # [s]
    host: str = "127.0.0.1"
    port: int = 8000
    viewer_port: int | None = 8080  # None: no viser viewer (--headless)
    extra_hosts: tuple[str, ...] = ()  # Host names accepted besides the bound address (tests: "testserver")
    token: str | None = None  # required on /api/ and /ws/ when set; a host beyond loopback needs one
    lock_lease_s: float = 5.0  # [s] the operator lock of a holder without a WebSocket, after its last request
    lock_grace_s: float = 2.0  # [s] the operator lock after its holder's last WebSocket closed
    sessions_dir: str = "out/sessions"  # where POST /api/sessions/start records and GET /api/sessions lists
    sessions_keep: int = KEEP_COUNT  # the retention rule (app.session.files.prune_sessions): files kept at most
    sessions_max_bytes: int = KEEP_BYTES  # [bytes] and their size together at most
    test_hooks: bool = False  # POST /api/sim/fault (a layer that raises, a NaN in the physics): tests only
