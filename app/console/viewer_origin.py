"""The viewer's websocket behind an Origin check: viser 1.1 has no option for it, so the `serve` viser's server
module calls is wrapped while the server starts, and a page from another origin is refused (403)."""

from __future__ import annotations

import viser


class OriginCheckingServe:
    """Stands in for `websockets.asyncio.server.serve` inside viser: the same call with a request check in
    front of viser's own, so the handshake of a page from another origin is refused (403) before viser sees
    it (app.console.security.origin_allowed: the viewer's own port, the port the connection arrived on, or the operator
    page's, on the bound host or a loopback name)."""

    def __init__(self, serve, host: str, page_ports: set[int]):
        from app.console.security import allowed_hosts_for

        self._serve = serve
        hosts = allowed_hosts_for(host)
        self._hosts = None if hosts is None else frozenset(hosts)
        self._page_ports = page_ports

    def __call__(self, handler, host, port, **kwargs):
        from app.console.security import origin_allowed, repeated_header

        inner = kwargs.get("process_request")
        hosts, page_ports = self._hosts, self._page_ports

        def process_request(connection, request):
            headers = request.headers
            repeated = repeated_header(headers.raw_items())
            if repeated is not None:
                return connection.respond(400, f"header {repeated} given more than once\n")
            if headers.get("Upgrade", "").lower() == "websocket":
                ports = {connection.local_address[1], *page_ports}
                if not origin_allowed(headers.get("Origin"), headers.get("Host", ""), hosts, ports):
                    return connection.respond(403, "this viewer only accepts its own page\n")
            return inner(connection, request) if inner is not None else None

        kwargs["process_request"] = process_request
        return self._serve(handler, host, port, **kwargs)


def viser_with_origin_check(host: str, port: int, page_ports: set[int], **kwargs) -> viser.ViserServer:
    """A ViserServer whose websocket checks the Origin header (viser 1.1 has no option for it: its server
    module's reference to websockets' `serve` is wrapped while the server starts)."""
    import types

    from viser.infra import _infra

    real = _infra.websockets
    wrapped = types.SimpleNamespace(**{k: getattr(real, k) for k in ("datastructures", "exceptions")})
    wrapped.asyncio = types.SimpleNamespace(server=types.SimpleNamespace(
        serve=OriginCheckingServe(real.asyncio.server.serve, host, page_ports),
        ServerConnection=real.asyncio.server.ServerConnection))
    _infra.websockets = wrapped
    try:
        server = viser.ViserServer(host=host, port=port, verbose=False, **kwargs)
    finally:
        _infra.websockets = real
    return server
