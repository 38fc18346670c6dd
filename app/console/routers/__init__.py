"""HTTP routers of the operator console, one per concern."""
