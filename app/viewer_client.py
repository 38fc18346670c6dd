"""Where viser's web client is: the console serves it at /viewer/ without importing viser itself."""

from __future__ import annotations

import importlib.util
from pathlib import Path


def client_html_path() -> Path:
    """viser's client (one self-contained HTML file). Served at /viewer/, the 3D view is an iframe of the
    operator page's own origin: the page then hears the keys pressed inside it (Esc and Space engage the
    e-stop with the focus in the 3D view); the client talks to the viewer's port (its `?websocket=` query)."""
    spec = importlib.util.find_spec("viser")
    if spec is None or spec.origin is None:
        raise FileNotFoundError("the viser package is not installed")
    return Path(spec.origin).parent / "client" / "build" / "index.html"
