"""Origins compared as scheme, host and port (app.console.security.origin_allowed), and the console refusing pages of
another port of the same host: a dev server, a notebook or `python -m http.server` in the operator's browser."""

import pytest
from starlette.websockets import WebSocketDisconnect

from app.console.security import origin_allowed, repeated_header, split_origin

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass

LOOPBACK = frozenset({"127.0.0.1", "localhost", "::1"})


@pytest.mark.parametrize("origin, parsed", [
    ("http://127.0.0.1:8000", ("http", "127.0.0.1", 8000)), ("http://LOCALHOST", ("http", "localhost", 80)),
    ("https://[::1]:9", ("https", "::1", 9)), ("null", None), ("ftp://a:1", None), ("http://a:99999", None),
    ("http://a:x", None), ("http://a/path", None), ("http://u@a", None), ("http://", None), ("", None)])
def test_an_origin_splits_into_scheme_host_and_port_or_is_malformed(origin, parsed):
    assert split_origin(origin) == parsed


@pytest.mark.parametrize("origin, host, allowed, ports, ok", [
    (None, "127.0.0.1:8000", LOOPBACK, None, True),  # a script: no Origin
    ("http://127.0.0.1:8000", "127.0.0.1:8000", LOOPBACK, None, True),  # the page itself
    ("http://localhost:8000", "127.0.0.1:8000", LOOPBACK, None, True),  # another loopback name, same port
    ("http://localhost:9999", "127.0.0.1:8000", LOOPBACK, None, False),  # another port: another site
    ("http://127.0.0.1", "127.0.0.1:8000", LOOPBACK, None, False),
    ("http://evil.example:8000", "127.0.0.1:8000", LOOPBACK, None, False),
    ("http://10.0.0.5:8000", "10.0.0.5:8000", None, None, True),  # bound to every interface: same origin
    ("http://10.0.0.6:8000", "10.0.0.5:8000", None, None, False),
    ("http://127.0.0.1:8000", "127.0.0.1:41234", LOOPBACK, (8000,), True),  # the door: the page's port
    ("http://127.0.0.1:41234", "127.0.0.1:41234", LOOPBACK, (8000,), False),  # not the page
    ("http://127.0.0.1:8000", "127.0.0.1:[bad", LOOPBACK, None, False),
])
def test_an_origin_is_allowed_only_from_the_consoles_own_pages(origin, host, allowed, ports, ok):
    assert origin_allowed(origin, host, allowed, ports) is ok


def test_a_header_given_twice_is_found_whatever_its_case():
    assert repeated_header([(b"host", b"a"), (b"origin", b"b"), (b"Origin", b"c")]) == "origin"
    assert repeated_header([(b"host", b"a"), (b"accept", b"b"), (b"accept", b"c")]) is None


@pytest.mark.parametrize("origin, status", [("http://testserver", 200), ("http://testserver:9999", 403),
                                            ("http://localhost:9999", 403)])
def test_control_requests_from_another_port_are_refused(client, origin, status):
    r = client.post("/api/motion/stop", json={}, headers={"origin": origin})
    assert r.status_code == status, r.text


@pytest.mark.parametrize("path", ["/ws/operator", "/ws/telemetry"])
def test_websockets_from_another_port_are_refused(client, path):
    with pytest.raises(WebSocketDisconnect) as exc:
        with client.websocket_connect(path, headers={"origin": "http://testserver:9999"}) as ws:
            ws.receive_text()
    assert exc.value.code == 1008
    with client.websocket_connect(path, headers={"origin": "http://testserver"}):
        pass


def test_a_request_with_two_origins_is_refused_naming_the_header(client):
    r = client.post("/api/motion/stop", json={}, headers=[("origin", "http://testserver"),
                                                          ("origin", "http://evil.example")])
    assert r.status_code == 400 and "origin" in r.json()["detail"]
