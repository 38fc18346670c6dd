"""viser's web client as the console serves it at /viewer/: viser's own page with one script added that hands
the keys pressed in the 3D view to the operator page (static/viewer_keys.js). Found without importing viser."""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

KEY_FORWARDER = '<script src="/static/viewer_keys.js"></script>'


def client_html_path() -> Path:
    """viser's client build: one self-contained HTML file."""
    spec = importlib.util.find_spec("viser")
    if spec is None or spec.origin is None:
        raise FileNotFoundError("the viser package is not installed")
    return Path(spec.origin).parent / "client" / "build" / "index.html"


@functools.cache
def client_html() -> str:
    """viser's client page with the key forwarder loaded first (in <head>, before viser's own module)."""
    html = client_html_path().read_text(encoding="utf-8")
    head = html.find("<head>")
    if head < 0:
        raise ValueError(f"{client_html_path()}: no <head> to add the key forwarder to")
    at = head + len("<head>")
    return html[:at] + KEY_FORWARDER + html[at:]
