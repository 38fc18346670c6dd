"""The operator console: the command line (cli.py) over four rooms: console/ (FastAPI app, viser view),
service/ (the robot process and its door), session/ (recordings) and lab/ (benches, experiments, studies)."""

import os

# before anything imports mujoco (see robot/__init__.py)
os.environ.setdefault("MUJOCO_GL", "egl")
