"""The two requests that must be fast under any load, answered before FastAPI's routing, dependency
injection and response models (about 2.5 ms of this machine's time per request): GET /api/state (the
cached document) and POST /api/estop. Their FastAPI routes stay, for OpenAPI and for the error answers:
anything unusual (no service, a service error) falls through to them."""

from __future__ import annotations

import json

from app.service import OperatorService, ServiceError

_JSON = [(b"content-type", b"application/json")]


async def _send(send, status: int, body: bytes) -> None:
    await send({"type": "http.response.start", "status": status,
                "headers": [*_JSON, (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


def estop_reply(ack) -> dict:
    """The POST /api/estop answer (app.schemas.EstopResponse) for the loop's acknowledgement."""
    return {"ok": True, "message": "hard e-stop already engaged" if ack.already_engaged else "hard e-stop engaged",
            "tick": ack.tick, "sim_time_s": ack.sim_time_s}


class HotPaths:
    """ASGI layer in front of the FastAPI app `api` (its `state.service` is the operator service)."""

    def __init__(self, api) -> None:
        self.api = api

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] == "http":
            service: OperatorService | None = getattr(self.api.state, "service", None)
            key = (scope["method"], scope["path"])
            if service is not None and key == ("GET", "/api/state"):
                try:
                    body = service.state_json()
                except ServiceError:
                    pass  # FastAPI's route answers with the error
                else:
                    await _send(send, 200, body)
                    return
            elif service is not None and key == ("POST", "/api/estop"):
                try:
                    ack = service.estop()
                except ServiceError:
                    pass
                else:
                    await _send(send, 200, json.dumps(estop_reply(ack)).encode())
                    return
        await self.api(scope, receive, send)
