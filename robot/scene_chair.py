"""The chair scene of [OP] VI, Fig. 8 ("manipulating a chair using its left hand"): a free chair on the floor, its
backrest toward the robot with a top rail the left hand grasps, for `hrp2-console experiment chair`
(app/lab/experiments/chair.py). The chair slides on its felt-padded feet and tips when pushed too high."""

from __future__ import annotations

from robot.parameters import fmt, vec
from robot.scenes import mjcf_scene_file

#: Seat: square, its top this high [m]; the legs 0.03 m square at its corners.
CHAIR_SEAT_SIZE_M = 0.40
CHAIR_SEAT_TOP_M = 0.45
CHAIR_SEAT_THICKNESS_M = 0.03
CHAIR_LEG_SIZE_M = 0.03
#: The backrest on the robot's side (-x of the chair frame): two posts and a round top rail along y, its axis
#: this high [m] and this thick (radius) [m]; the 85 mm JRL hand closes across it (on a 28 mm rail the jaw ends
#: 3 deg from its closing limit, where the grasp reads "nothing held").
CHAIR_RAIL_HEIGHT_M = 0.78
CHAIR_RAIL_RADIUS_M = 0.02
CHAIR_MASS_KG = 5.0
#: Felt pads on a smooth floor: sliding friction 0.2 (the legs' priority makes it the contact's coefficient,
#: not the floor's 1.0). Pushed horizontally at the rail a 5 kg chair slides at 0.2 x 49 N = 9.8 N; it tips
#: about its front legs (0.215 m ahead of its mass centre) at 49 N x 0.215 m / 0.78 m = 13.5 N: it slides first.
CHAIR_LEG_FRICTION = (0.2, 0.005, 0.0001)
CHAIR_RGBA = {"wood": "0.6 0.4 0.2 1", "rail": "0.35 0.22 0.1 1"}
#: The chair frame (floor, under the seat's centre) in the generated file: its rail 0.34 m ahead of the robot,
#: in front of the left shoulder (nearer the body's middle the elbow met the chest; experiments place it).
CHAIR_START_M = (0.525, 0.30)


def rail_x_in_chair_m() -> float:
    """x of the rail's axis in the chair frame [m] (the backrest's posts are flush with the seat's back edge)."""
    return -CHAIR_SEAT_SIZE_M / 2 + CHAIR_LEG_SIZE_M / 2


def chair_body_lines(pos) -> list[str]:
    s, leg, top, t = CHAIR_SEAT_SIZE_M / 2, CHAIR_LEG_SIZE_M / 2, CHAIR_SEAT_TOP_M, CHAIR_SEAT_THICKNESS_M
    leg_h = (top - t) / 2
    xr = rail_x_in_chair_m()
    post_h = (CHAIR_RAIL_HEIGHT_M - top) / 2
    m = CHAIR_MASS_KG
    # the mass centre a little behind and above the seat's centre (the backrest); inertia of a 0.4 m cube
    inertia = m * (2 * 0.4 ** 2) / 12
    ind = "      "
    lines = [f'    <body name="chair" pos="{vec(pos)}">',
             '      <freejoint name="chair_free"/>',
             f'{ind}<inertial pos="-0.03 0 0.42" mass="{fmt(m)}" diaginertia="{vec((inertia,) * 3)}"/>',
             f'{ind}<geom name="chair_seat" type="box" pos="0 0 {fmt(top - t / 2)}" size="{vec((s, s, t / 2))}" '
             'material="chair_wood"/>']
    for k, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1))):
        p = (sx * (s - leg), sy * (s - leg), leg_h)
        lines.append(f'{ind}<geom name="chair_leg{k}" type="box" pos="{vec(p)}" size="{vec((leg, leg, leg_h))}" '
                     f'material="chair_wood" friction="{vec(CHAIR_LEG_FRICTION)}" priority="1"/>')
    for k, sy in enumerate((1, -1)):
        p = (xr, sy * (s - leg), top + post_h)
        lines.append(f'{ind}<geom name="chair_post{k}" type="box" pos="{vec(p)}" size="{vec((leg, leg, post_h))}" '
                     'material="chair_wood"/>')
    lines.append(f'{ind}<geom name="chair_rail" type="cylinder" pos="{vec((xr, 0.0, CHAIR_RAIL_HEIGHT_M))}" '
                 f'zaxis="0 1 0" size="{vec((CHAIR_RAIL_RADIUS_M, s))}" material="chair_rail"/>')
    lines.append("    </body>")
    return lines


def mjcf_scene_chair(params: dict) -> str:
    pos = (*CHAIR_START_M, 0.0)
    sections = ["  <asset>", *(f'    <material name="chair_{n}" rgba="{rgba}"/>' for n, rgba in CHAIR_RGBA.items()),
                "  </asset>"]
    return mjcf_scene_file(params, "hrp2 chair scene", chair_body_lines(pos), (*pos, 1.0, 0.0, 0.0, 0.0), sections)
