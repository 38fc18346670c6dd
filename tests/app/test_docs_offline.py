"""/docs and the operator page work without the internet: Swagger UI's files come from the pinned
swagger-ui-bundle-v2 package, the page's modules from static/, all served by the console itself; nothing in
either page points elsewhere."""

from __future__ import annotations

import re
from urllib.parse import urljoin

import pytest

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


def test_docs_load_swagger_ui_from_the_console_only(client):
    r = client.get("/docs")
    assert r.status_code == 200
    html = r.text
    external = re.findall(r"""(?:src|href)\s*=\s*["'](https?:)?//""", html)
    assert not external, external
    assert "cdn" not in html.lower()
    for url in re.findall(r"""(?:src|href)\s*=\s*["'](/[^"']+)["']""", html):
        asset = client.get(url)
        assert asset.status_code == 200 and len(asset.content) > 500, url
    assert client.get("/static/swagger-ui/swagger-ui-bundle.js").headers["content-type"].startswith(
        ("text/javascript", "application/javascript"))
    assert client.get("/openapi.json").json()["openapi"].startswith("3.1")
    assert client.get("/redoc").status_code == 404  # ReDoc would load from a CDN: not offered


def imports_of(source: str) -> list[str]:
    """The modules an ES module imports or re-exports from ("./x.js": relative to it)."""
    return re.findall(r"""^(?:import|export)\s[^;]*?\sfrom\s+["']([^"']+)["'];""", source, re.M)


def test_the_operator_page_loads_its_modules_from_the_console_as_javascript(client):
    html = client.get("/").text
    scripts = re.findall(r"""<script\b[^>]*\bsrc\s*=\s*["']([^"']+)["']""", html)
    assert scripts[:2] == ["/static/js/estop.js", "/static/console.js"], scripts
    assert all(f'<script type="module" src="{s}"></script>' in html for s in scripts[:2])
    seen: dict[str, str] = {}
    todo = list(scripts)
    while todo:
        url = todo.pop()
        if url in seen:
            continue
        r = client.get(url)
        assert r.status_code == 200, url
        assert r.headers["content-type"].startswith(("text/javascript", "application/javascript")), url
        seen[url] = r.text
        todo += [urljoin(url, i) for i in imports_of(r.text)]
    assert len(seen) >= 8 and all(u.startswith("/static/") for u in seen), sorted(seen)
    # the E-STOP's module loads first and imports nothing: it works whatever else fails to load
    assert imports_of(seen["/static/js/estop.js"]) == []
    assert "/static/js/estop.js" in {urljoin("/static/console.js", i) for i in imports_of(seen["/static/console.js"])}
