"""The console: FastAPI app, viser view, the robot process and its service, benchmarks and experiments."""

import os

# before anything imports mujoco (see robot/__init__.py)
os.environ.setdefault("MUJOCO_GL", "egl")
