"""The simulated HRP-2 No.10: model files, their generator and the MuJoCo plant. Imports no other package."""

import os

# MuJoCo picks its OpenGL backend when it is first imported: headless EGL unless the user chose another
# (without a display the default GLFW would make the head cameras' renderer wait for ever)
os.environ.setdefault("MUJOCO_GL", "egl")
