"""Names shared by the model files, the plant and the controller (OpenHRP order)."""

from __future__ import annotations

from pathlib import Path

#: The 30 joints in OpenHRP order: the index of a joint in every joint vector of the project.
JOINT_NAMES: tuple[str, ...] = (
    *(f"RLEG_JOINT{i}" for i in range(6)),
    *(f"LLEG_JOINT{i}" for i in range(6)),
    "CHEST_JOINT0",
    "CHEST_JOINT1",
    "HEAD_JOINT0",
    "HEAD_JOINT1",
    *(f"RARM_JOINT{i}" for i in range(7)),
    *(f"LARM_JOINT{i}" for i in range(7)),
)
NUM_JOINTS = len(JOINT_NAMES)

#: Default joint groups (hrpsys `addJointGroup` names), as index tuples into JOINT_NAMES.
JOINT_GROUPS: dict[str, tuple[int, ...]] = {
    "rleg": tuple(range(0, 6)),
    "lleg": tuple(range(6, 12)),
    "torso": (12, 13),
    "head": (14, 15),
    "rarm": tuple(range(16, 23)),
    "larm": tuple(range(23, 30)),
}

#: 6-axis force/torque sensors: name -> link carrying the sensor site.
FORCE_SENSORS: dict[str, str] = {
    "rfsensor": "RLEG_LINK5",
    "lfsensor": "LLEG_LINK5",
    "rhsensor": "RARM_LINK5",
    "lhsensor": "LARM_LINK5",
}
FORCE_SENSOR_NAMES: tuple[str, ...] = tuple(FORCE_SENSORS)

#: End-effector frames (site names in MJCF, frame names in URDF).
END_EFFECTORS: dict[str, str] = {
    "rleg": "rleg_end",   # sole centre below the ankle, 0.105 m
    "lleg": "lleg_end",
    "rarm": "rarm_end",   # between the gripper jaws
    "larm": "larm_end",
}

BASE_LINK = "BODY"

MODEL_DIR = Path(__file__).resolve().parent / "hrp2"
MJCF_ROBOT = MODEL_DIR / "hrp2.xml"
MJCF_SCENE = MODEL_DIR / "scene.xml"
URDF = MODEL_DIR / "hrp2.urdf"
PARAMETERS_JSON = Path(__file__).resolve().parent / "data" / "hrp2_parameters.json"


def joint_index(name: str) -> int:
    """Index of `name` in JOINT_NAMES; the error lists the valid names."""
    try:
        return JOINT_NAMES.index(name)
    except ValueError:
        raise KeyError(f"unknown joint {name!r}; valid joints: {', '.join(JOINT_NAMES)}") from None

#: Sensor origins in the carrying link's frame [m] (the MJCF sites and the controller's frames).
#: Feet: at the sole below the ankle; wrists: at the ARM_JOINT5 axis (assumed placement, see README).
FORCE_SENSOR_POS_IN_LINK: dict[str, tuple[float, float, float]] = {
    "rfsensor": (0.0, 0.0, -0.105),
    "lfsensor": (0.0, 0.0, -0.105),
    "rhsensor": (0.0, 0.0, 0.0),
    "lhsensor": (0.0, 0.0, 0.0),
}
