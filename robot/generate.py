"""Generate the HRP-2 No.10 model files (MJCF robot, MJCF scene, URDF) from robot/data/hrp2_parameters.json.

Run `python -m robot.generate [output_dir]`; the output is deterministic (byte-identical on re-run).
README.md, LICENSE and CHANGELOG.md in robot/hrp2/ are hand-written and never touched here.
"""

from __future__ import annotations

import sys
from pathlib import Path

from robot.names import MODEL_DIR
from robot.parameters import half_sitting_deg, joint_limits_deg, load_parameters
from robot.robot_model import (
    CAMERAS,
    FINGER_PAD_DEPTH_M,
    FINGER_PAD_RADIUS_M,
    GRIP_FORCE_LIMIT_N,
    SERVO_CLASSES,
    grasp_centre,
    gripper_fixed_jaw_face_x,
    gripper_pivot,
    mjcf_robot,
    urdf,
)
from robot.scene_chair import mjcf_scene_chair
from robot.scene_fridge import mjcf_scene_fridge
from robot.scene_trash import mjcf_scene_trash
from robot.scenes import (
    CAN_DIAMETER_M,
    CAN_HEIGHT_M,
    DOOR_FACE_X_M,
    DOOR_HINGE_Y_M,
    DOOR_KNOB_M,
    EXPO_CAN_FROM_EDGE_RANGE_M,
    EXPO_TABLE_CENTRE_Y_M,
    EXPO_TABLE_LEG_INSET_M,
    EXPO_TABLE_LEG_SIZE_M,
    EXPO_TABLE_NEAR_EDGE_X_M,
    EXPO_TABLE_SIZE_M,
    FRONT_WALL_X_M,
    LEFT_WALL_Y_M,
    TRASH_BOX_CENTRE_M,
    TRASH_BOX_HOLE_M,
    TRASH_BOX_OUTER_M,
    TRASH_BOX_WALL_M,
    UNKNOWN_OBJECT_SIZE_M,
    VALVE_RING_RADIUS_M,
    VALVE_TUBE_RADIUS_M,
    mjcf_scene,
    mjcf_scene_door,
    mjcf_scene_expo,
    mjcf_scene_valve,
    mjcf_scene_wall,
)
from robot.silhouette import SILHOUETTE_GROUP, SILHOUETTE_RGBA, silhouette

#: the names the rest of the project takes from here (defined in robot.parameters, robot.robot_model and
#: robot.scenes)
__all__ = [
    "CAMERAS", "CAN_DIAMETER_M", "CAN_HEIGHT_M", "DOOR_FACE_X_M", "DOOR_HINGE_Y_M", "DOOR_KNOB_M",
    "EXPO_CAN_FROM_EDGE_RANGE_M", "EXPO_TABLE_CENTRE_Y_M", "EXPO_TABLE_LEG_INSET_M", "EXPO_TABLE_LEG_SIZE_M",
    "EXPO_TABLE_NEAR_EDGE_X_M", "EXPO_TABLE_SIZE_M", "FINGER_PAD_DEPTH_M", "FINGER_PAD_RADIUS_M", "FRONT_WALL_X_M",
    "GENERATED_FILES", "GRIP_FORCE_LIMIT_N", "LEFT_WALL_Y_M", "SERVO_CLASSES", "TRASH_BOX_CENTRE_M",
    "TRASH_BOX_HOLE_M", "TRASH_BOX_OUTER_M", "TRASH_BOX_WALL_M", "UNKNOWN_OBJECT_SIZE_M", "VALVE_RING_RADIUS_M",
    "VALVE_TUBE_RADIUS_M", "generate", "grasp_centre", "gripper_fixed_jaw_face_x", "gripper_pivot",
    "half_sitting_deg", "joint_limits_deg", "load_parameters", "main", "render",
]


# ----------------------------------------------------------------------------------------------- main

GENERATED_FILES = ("hrp2.xml", "scene.xml", "scene_wall.xml", "scene_valve.xml", "scene_door.xml", "scene_expo.xml",
                   "scene_fridge.xml", "scene_trash.xml", "scene_chair.xml", "hrp2.urdf")


def render(params: dict | None = None) -> dict[str, str]:
    """The generated files' contents: file name -> text."""
    params = load_parameters() if params is None else params
    return {"hrp2.xml": mjcf_robot(params, silhouette(params), SILHOUETTE_GROUP, SILHOUETTE_RGBA),
            "scene.xml": mjcf_scene(params),
            "scene_wall.xml": mjcf_scene_wall(params), "scene_valve.xml": mjcf_scene_valve(params),
            "scene_door.xml": mjcf_scene_door(params), "scene_expo.xml": mjcf_scene_expo(params),
            "scene_fridge.xml": mjcf_scene_fridge(params),
            "scene_trash.xml": mjcf_scene_trash(params),
            "scene_chair.xml": mjcf_scene_chair(params),
            "hrp2.urdf": urdf(params)}


def generate(output_dir: str | Path = MODEL_DIR) -> list[Path]:
    """Write the generated files into `output_dir`; return their paths."""
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, text in render().items():
        path = out / name
        path.write_text(text)
        paths.append(path)
    return paths


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    for path in generate(argv[0] if argv else MODEL_DIR):
        print(path.name)


if __name__ == "__main__":
    main()
