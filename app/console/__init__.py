"""The web console: the FastAPI app (main.py), its routers, WebSockets, front door and state document, and the
viser 3D view; it serves the operator service (app.service) and never needs the lab (app.lab)."""
