"""Draws docs/img/robot_silhouette.png: HRP-2 No.10 as the 3D view draws it (robot/silhouette.py where there is
one, the collision shapes elsewhere), from the front, the back and at the right hand with its gripper open:

    MUJOCO_GL=egl python docs/img/robot_silhouette.py
"""

import math
from pathlib import Path

import mujoco
import numpy as np
from PIL import Image

from app.console.viewer_meshes import drawn_geoms
from robot.names import MODEL_DIR

OUT = Path(__file__).with_name("robot_silhouette.png")
#: (azimuth [deg], elevation [deg], distance [m], look-at height [m] or a body's name)
VIEWS = ((200, -10, 1.9, 0.85), (340, -15, 1.4, 1.1), (90, -10, 0.5, "RARM_LINK5"))
GRIPPER_OPEN_RAD = math.radians(-40.0)  # RARM_JOINT6 opened (its range -60 .. 16 deg)


def main() -> None:
    model = mujoco.MjModel.from_xml_path(str(MODEL_DIR / "scene.xml"))
    drawn = set(drawn_geoms(model))
    for g in range(model.ngeom):  # what the view draws, alone: the rest made invisible
        if g not in drawn:
            model.geom_rgba[g, 3] = 0.0
    data = mujoco.MjData(model)
    data.qpos[model.jnt_qposadr[model.joint("RARM_JOINT6").id]] = GRIPPER_OPEN_RAD
    mujoco.mj_forward(model, data)
    option = mujoco.MjvOption()
    option.geomgroup[:] = 1
    renderer = mujoco.Renderer(model, 480, 400)
    images = []
    for azimuth, elevation, distance, at in VIEWS:
        camera = mujoco.MjvCamera()
        camera.azimuth, camera.elevation, camera.distance = azimuth, elevation, distance
        camera.lookat[:] = data.xpos[model.body(at).id] if isinstance(at, str) else (0.0, 0.0, at)
        renderer.update_scene(data, camera, option)
        images.append(renderer.render())
    Image.fromarray(np.hstack(images)).save(OUT, optimize=True)
    print(OUT)


if __name__ == "__main__":
    main()
