"""The two requests that must be fast under any load, answered before FastAPI's routing, dependency
injection and response models (about 2.5 ms of this machine's time per request): GET /api/state (the
cached document) and POST /api/estop. Their FastAPI routes stay, for OpenAPI and for the error answers:
anything unusual (no service, a service error) falls through to them."""

from __future__ import annotations

import json
import re

from app.console.state import with_console_state
from app.service import OperatorService, ServiceError

_JSON = [(b"content-type", b"application/json")]


async def _send(send, status: int, body: bytes) -> None:
    await send({"type": "http.response.start", "status": status,
                "headers": [*_JSON, (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


def estop_press_header(scope) -> str | None:
    """The request's X-Estop-Press header (None: absent); its value is checked by the caller."""
    for name, value in scope.get("headers", ()):
        if name == b"x-estop-press":
            return value.decode("latin-1")
    return None


class HotPaths:
    """ASGI layer in front of the FastAPI app `api` (its `state.service` is the operator service)."""

    def __init__(self, api) -> None:
        self.api = api
        self._methods: list | None = None  # [(path pattern, methods)] from the OpenAPI document

    def allowed_methods(self, scope) -> set[str] | None:
        """The methods the API documents for this path (None: a path it does not document, such as the page
        and the static files)."""
        if self._methods is None:
            table = []
            for template, ops in self.api.openapi().get("paths", {}).items():
                pattern = re.compile("^" + re.sub(r"\\{[^/]+\\}", "[^/]+", re.escape(template)) + "$")
                table.append((pattern, "{" not in template, {m.upper() for m in ops}))
            self._methods = table
        path = scope["path"]
        found = [(literal, methods) for pattern, literal, methods in self._methods if pattern.match(path)]
        # a path written out (/api/sessions/start) is that path only, not also a value of a parameter
        # (/api/sessions/{name}): its methods are the ones it documents
        literal = [methods for is_literal, methods in found if is_literal]
        found = literal or [methods for _, methods in found]
        return set().union(*found) if found else None

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] == "http":
            allowed = self.allowed_methods(scope)
            if allowed is not None and scope["method"] not in allowed | ({"HEAD"} if "GET" in allowed else set()):
                body = json.dumps({"detail": f"{scope['method']} is not a method of {scope['path']}; "
                                             f"allowed: {', '.join(sorted(allowed))}"}).encode()
                await send({"type": "http.response.start", "status": 405, "headers": [
                    *_JSON, (b"content-length", str(len(body)).encode()),
                    (b"allow", ", ".join(sorted(allowed)).encode())]})
                await send({"type": "http.response.body", "body": body})
                return
            service: OperatorService | None = getattr(self.api.state, "service", None)
            key = (scope["method"], scope["path"])
            if service is not None and key == ("GET", "/api/state"):
                try:
                    body = with_console_state(service.state_json(), getattr(self.api.state, "lock", None),
                                              getattr(self.api.state, "journal", None))
                except ServiceError:
                    pass  # FastAPI's route answers with the error
                else:
                    await _send(send, 200, body)
                    return
            elif service is not None and key == ("POST", "/api/estop"):
                try:
                    ack = service.estop(estop_press_header(scope))
                except ServiceError:
                    pass  # FastAPI's route answers with the error
                else:
                    await _send(send, 200 if ack.engaged else 409, json.dumps(ack.reply()).encode())
                    return
        await self.api(scope, receive, send)
