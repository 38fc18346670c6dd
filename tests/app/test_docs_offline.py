"""/docs works without the internet: Swagger UI's files come from the pinned swagger-ui-bundle-v2 package,
served by the console itself; nothing in the page points elsewhere."""

from __future__ import annotations

import re


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
