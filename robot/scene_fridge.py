"""The fridge scene of [OP] VI, Fig. 8: a fridge with a hinged door (handle for the JRL hand) and a 300 ml can on a
shelf inside, in front of the robot. Colours are chosen for the head cameras: a blue door, a yellow handle, a
red can (the only red), a grey cabinet (low saturation)."""

# Frames: the robot stands at the origin facing +x (the `home` keyframe). The fridge is a mocap body (static for
# the physics, placed and turned by robot.scene_objects.place_object) whose origin is on the floor below the
# door's hinge, x into the fridge, y to the robot's left; the door hangs on a vertical hinge at the cabinet's
# front right edge and opens toward the robot (positive angle about +z). The handle is a vertical bar on the
# door's face at FRIDGE_HANDLE_FROM_HINGE_M from the hinge; the can stands on the shelf at the right hand's
# reach height standing (robot/hrp2/README.md's reach: the can taken at 0.75-0.80 m).

from __future__ import annotations

import math

from robot.parameters import fmt, vec
from robot.scenes import (
    CAN_CONDIM,
    CAN_DIAMETER_M,
    CAN_FRICTION,
    CAN_HEIGHT_M,
    CAN_MASS_KG,
    CAN_SOLREF,
    EXPO_RGBA,
    box_geom,
    free_body_lines,
    mjcf_scene_file,
)

#: The hinge (the fridge frame's origin) in the world at the default pose [m]: the cabinet's front face 0.58 m
#: ahead of the robot, its right edge 0.42 m to the robot's right: the handle 0.20 m right of the body's middle,
#: where the right hand takes a can (take_can: 0.19-0.28 m; nearer the middle the wrist met the chest).
FRIDGE_HINGE_M = (0.58, -0.42)
FRIDGE_CABINET_M = (0.40, 0.60, 1.10)  # depth (x), width (y), height (z) [m]
FRIDGE_WALL_M = 0.02  # walls, top, back and the shelf [m]
FRIDGE_SHELF_TOP_M = 0.72  # the shelf's top face the can stands on [m]
FRIDGE_DOOR_THICKNESS_M = 0.03
FRIDGE_DOOR_GAP_M = 0.01  # the door's bottom above the floor, its top below the cabinet's [m]
FRIDGE_DOOR_MASS_KG = 4.0
FRIDGE_DOOR_RANGE_DEG = (0.0, 110.0)  # 0 closed (the stop), positive = open toward the robot
FRIDGE_DOOR_DAMPING = 1.0  # N m s/rad
FRIDGE_DOOR_FRICTIONLOSS = 0.3  # N m
#: The handle: a vertical bar [m] this far from the hinge along the door (not at the door's free edge: there
#: the right hand would cross the body's middle and the left hand would have no room beside the door), its axis
#: this far in front of the door's face, between these heights, of this radius (a 40 mm bar: the JRL hand's jaws
#: open to 0.10 m; a 30 mm bar, pulled, slipped out between the pads). Its contacts resist turning (condim 6, as the
#: can's) and grip (friction 1.5: at 1.0 the bar slid out at 24 deg).
FRIDGE_HANDLE_FROM_HINGE_M = 0.22
FRIDGE_HANDLE_STANDOFF_M = 0.045
FRIDGE_HANDLE_Z_M = (0.65, 0.95)
FRIDGE_HANDLE_RADIUS_M = 0.02
FRIDGE_HANDLE_FRICTION = (1.5, 0.02, 0.001)
#: The can's default place on the shelf, in the fridge frame [m] (x in from the cabinet's front, y from the hinge):
#: 0.02 m right of the body's middle, where the left hand turned 45 deg takes it (0.07 m farther left its palm met
#: the cabinet's left wall), 0.63 m ahead: beyond the 0.56 m a standing hand reaches (the left hand leans in; with the
#: fridge nearer, the door's arc came so close to the body that the right arm stopped it at 24 deg).
FRIDGE_CAN_IN_FRIDGE_M = (0.05, 0.40)
FRIDGE_CAN_Y_RANGE_M = (0.38, 0.42)  # the can's y places the experiment draws from (fridge frame) [m]

FRIDGE_RGBA = {
    "cabinet": "0.82 0.82 0.8 1",  # light grey, low saturation
    "shelf": "0.7 0.72 0.72 1",
    "door": "0.15 0.35 0.8 1",  # saturated blue: the door's face for its plane
    "handle": "0.95 0.8 0.05 1",  # saturated yellow: the only yellow, for the handle
    "can": EXPO_RGBA["can"],  # the EXPO can's red
}


def fridge_materials() -> list[str]:
    return ["  <asset>", *(f'    <material name="fridge_{n}" rgba="{rgba}"/>' for n, rgba in FRIDGE_RGBA.items()),
            "  </asset>"]


def _box(name: str, lo, hi, material: str, ind: str = "      ") -> str:
    return box_geom(name, lo, hi, material, ind=ind).replace('material="expo_', 'material="fridge_')


def fridge_cabinet_lines() -> list[str]:
    """The cabinet (fridge frame): two sides, back, bottom, top and the shelf, open at the front (x = 0)."""
    d, w, h = FRIDGE_CABINET_M
    t = FRIDGE_WALL_M
    s = FRIDGE_SHELF_TOP_M
    return [
        _box("fridge_side_right", (0.0, 0.0, 0.0), (d, t, h), "cabinet"),
        _box("fridge_side_left", (0.0, w - t, 0.0), (d, w, h), "cabinet"),
        _box("fridge_back", (d - t, t, 0.0), (d, w - t, h), "cabinet"),
        _box("fridge_bottom", (0.0, t, 0.0), (d - t, w - t, t), "cabinet"),
        _box("fridge_top", (0.0, t, h - t), (d - t, w - t, h), "cabinet"),
        _box("fridge_shelf", (0.0, t, s - t), (d - t, w - t, s), "shelf"),
    ]


def fridge_door_lines() -> list[str]:
    """The door on its hinge (at the fridge frame's origin, axis +z) with the handle bar on its face."""
    _, w, h = FRIDGE_CABINET_M
    t, gap, m = FRIDGE_DOOR_THICKNESS_M, FRIDGE_DOOR_GAP_M, FRIDGE_DOOR_MASS_KG
    dh = h - 2 * gap
    inertia = (m / 12 * (w * w + dh * dh), m / 12 * (t * t + dh * dh), m / 12 * (t * t + w * w))
    lo, hi = (math.radians(v) for v in FRIDGE_DOOR_RANGE_DEG)
    hx = -t - FRIDGE_HANDLE_STANDOFF_M
    hy = FRIDGE_HANDLE_FROM_HINGE_M
    z0, z1 = FRIDGE_HANDLE_Z_M
    ind = "        "
    lines = [
        '      <body name="fridge_door" pos="0 0 0">',
        f'{ind}<inertial pos="{vec((-t / 2, w / 2, gap + dh / 2))}" mass="{fmt(m)}" diaginertia="{vec(inertia)}"/>',
        f'{ind}<joint name="fridge_door_hinge" type="hinge" axis="0 0 1" range="{fmt(lo)} {fmt(hi)}" '
        f'damping="{fmt(FRIDGE_DOOR_DAMPING)}" frictionloss="{fmt(FRIDGE_DOOR_FRICTIONLOSS)}" solreflimit="0.005 1"/>',
        _box("fridge_door_panel", (-t, 0.0, gap), (0.0, w, gap + dh), "door", ind),
        f'{ind}<geom name="fridge_handle" type="cylinder" fromto="{vec((hx, hy, z0, hx, hy, z1))}" '
        f'size="{fmt(FRIDGE_HANDLE_RADIUS_M)}" material="fridge_handle" friction="{vec(FRIDGE_HANDLE_FRICTION)}" '
        f'condim="{CAN_CONDIM}" solref="{vec(CAN_SOLREF)}"/>',
    ]
    for k, z in enumerate((z0 + 0.02, z1 - 0.02)):
        lines.append(f'{ind}<geom name="fridge_handle_post{k}" type="box" pos="{vec(((hx - t) / 2, hy, z))}" '
                     f'size="{vec(((-t - hx) / 2, 0.008, 0.01))}" material="fridge_handle"/>')
    lines.append("      </body>")
    return lines


def fridge_can_start_m() -> tuple[float, float, float]:
    """The can's centre in the world at the default fridge pose [m]."""
    return (FRIDGE_HINGE_M[0] + FRIDGE_CAN_IN_FRIDGE_M[0], FRIDGE_HINGE_M[1] + FRIDGE_CAN_IN_FRIDGE_M[1],
            FRIDGE_SHELF_TOP_M + CAN_HEIGHT_M / 2)


def mjcf_scene_fridge(params: dict) -> str:
    r, h, m = CAN_DIAMETER_M / 2, CAN_HEIGHT_M, CAN_MASS_KG
    can_inertia = (m * (3 * r * r + h * h) / 12, m * (3 * r * r + h * h) / 12, m * r * r / 2)
    can_geom = (f'<geom name="can" type="cylinder" size="{fmt(r)} {fmt(h / 2)}" material="fridge_can" '
                f'condim="{CAN_CONDIM}" friction="{vec(CAN_FRICTION)}" solref="{vec(CAN_SOLREF)}"/>')
    can_pos = fridge_can_start_m()
    world = [
        f'    <body name="fridge" mocap="true" pos="{vec((*FRIDGE_HINGE_M, 0.0))}">',
        *fridge_cabinet_lines(),
        *fridge_door_lines(),
        "    </body>",
        *free_body_lines("can", can_pos, m, can_inertia, can_geom),
    ]
    sections = [*fridge_materials(),
                "  <contact>", '    <exclude body1="fridge" body2="fridge_door"/>', "  </contact>",
                "  <sensor>", '    <jointpos name="fridge_door_angle" joint="fridge_door_hinge"/>', "  </sensor>"]
    extra_qpos = (0.0, *can_pos, 1.0, 0.0, 0.0, 0.0)
    return mjcf_scene_file(params, "hrp2 fridge scene", world, extra_qpos, sections)
