"""The unknown-trash scene of [OP] VI, Fig. 8: a crumpled piece of trash on the floor (no model of it anywhere in
the robot: it is found by its colour alone) and the EXPO trash box with its 120 x 280 mm hole, for
`hrp2-console experiment trash` (app/lab/experiments/trash.py)."""

from __future__ import annotations

import math

from robot.parameters import fmt, vec
from robot.scenes import CAN_CONDIM, CAN_FRICTION, CAN_SOLREF, expo_materials, expo_trash_box_lines, mjcf_scene_file

#: The trash: a crumpled plastic carton, a compound of a flat base, two lumps leaning different ways and a dented
#: upper part ((type, size [m], position [m] in the body frame, (axis angle about x, about y) [deg])). About 60 mm
#: across at every height (the 85 mm JRL hand opens to 0.10 m), 0.20 m tall, so the squatting robot's side grasp
#: takes it 30 mm below its top (as the EXPO carton, app/lab/experiments/floor_object.py), on the upper part's
#: flat sides (with a 20 mm neck on top, the grasp landed 1 cm from an edge and the trash slipped out as the robot
#: walked). Body origin: mid-height.
TRASH_PARTS = (
    ("cylinder", (0.029, 0.015), (0.0, 0.0, -0.085), (0.0, 0.0)),
    ("ellipsoid", (0.030, 0.026, 0.040), (0.004, -0.003, -0.045), (8.0, -6.0)),
    ("ellipsoid", (0.025, 0.030, 0.035), (-0.004, 0.004, 0.005), (-10.0, 12.0)),
    ("box", (0.024, 0.022, 0.045), (0.003, 0.0, 0.050), (8.0, 4.0)),
)
TRASH_HEIGHT_M = 0.20  # base bottom (-0.10) to the upper part's top (0.05 + 0.045, and its lean)
TRASH_MASS_KG = 0.12
#: Saturated orange: the only orange in the scene (the robot is grey, the floor blue-grey, the lid green), so a
#: colour segmentation finds it without a model of its shape.
TRASH_RGBA = "0.95 0.5 0.08 1"
#: Where the generated file puts it (experiments place it): ~1 m ahead of the robot.
TRASH_START_M = (1.0, 0.0)
#: The trash box's hole centre (floor) in this scene: beyond the trash, seen from where the robot picks it up
#: without turning (within 30 deg of ahead), 0.27 m beyond the farthest trash placement.
TRASH_SCENE_BOX_M = (2.1, 0.0)
#: MuJoCo's noslip post-solver in this scene: its soft contacts let the held trash creep out of a grip that
#: Coulomb friction locks (pads mu 1.2 on its 8 deg tilted upper part): 8 mm along the jaws in 10 s, then out
#: (docs/fig8-tasks.md); with it, none.
TRASH_SCENE_NOSLIP_ITERATIONS = 10


def trash_part_lines(ind: str = "      ") -> list[str]:
    lines = []
    for k, (kind, size, pos, (ax_deg, ay_deg)) in enumerate(TRASH_PARTS):
        ax, ay = math.radians(ax_deg) / 2, math.radians(ay_deg) / 2
        # about x, then about the world's y: q = q_y * q_x
        q = (math.cos(ay) * math.cos(ax), math.cos(ay) * math.sin(ax), math.sin(ay) * math.cos(ax),
             -math.sin(ay) * math.sin(ax))
        lines.append(f'{ind}<geom name="trash_part{k}" type="{kind}" size="{vec(size)}" pos="{vec(pos)}" '
                     f'quat="{vec(tuple(round(v, 9) for v in q))}" material="trash" condim="{CAN_CONDIM}" '
                     f'friction="{vec(CAN_FRICTION)}" solref="{vec(CAN_SOLREF)}"/>')
    return lines


def trash_body_lines(pos) -> list[str]:
    """The trash as a free body; its inertia that of a 0.06 x 0.06 x 0.20 m block of its mass."""
    m, a, h = TRASH_MASS_KG, 0.06, TRASH_HEIGHT_M
    inertia = (m * (a * a + h * h) / 12, m * (a * a + h * h) / 12, m * (2 * a * a) / 12)
    return [f'    <body name="trash" pos="{vec(pos)}">',
            '      <freejoint name="trash_free"/>',
            f'      <inertial pos="0 0 0" mass="{fmt(m)}" diaginertia="{vec(inertia)}"/>',
            *trash_part_lines(),
            "    </body>"]


def mjcf_scene_trash(params: dict) -> str:
    pos = (*TRASH_START_M, 0.10 + 0.001)
    sections = [*expo_materials()[:-1], f'    <material name="trash" rgba="{TRASH_RGBA}"/>', "  </asset>",
                f'  <option noslip_iterations="{TRASH_SCENE_NOSLIP_ITERATIONS}"/>']
    world = [*expo_trash_box_lines(TRASH_SCENE_BOX_M), *trash_body_lines(pos)]
    return mjcf_scene_file(params, "hrp2 trash scene", world, (*pos, 1.0, 0.0, 0.0, 0.0), sections)
