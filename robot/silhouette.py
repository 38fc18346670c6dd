"""HRP-2 No.10's silhouette for the operator's eye: chest and backpack, the head with its camera windows, the
JRL hand's two fingers in a colour of their own so the gripper's opening reads at a glance.

Drawing only: the geoms are of class "silhouette" (contype 0, conaffinity 0, no mass since the model takes its
inertia from the parameters), in geom group 5, which MuJoCo's renderers, and so the head cameras, leave out by
default: the physics and the robot's own images are the ones of the collision shapes, as before."""

from __future__ import annotations

from robot.robot_model import (
    CAMERAS,
    FINGER_PAD_DEPTH_M,
    FINGER_PAD_RADIUS_M,
    FINGER_WIDTH_M,
    FIXED_JAW_BOTTOM_BELOW_PIVOT_M,
    FIXED_JAW_THICKNESS_M,
    Geom,
    bbox,
    box_from_bbox,
    gripper_fixed_jaw_face_x,
    gripper_pivot,
)

#: The MJCF geom group of the silhouette: not in MuJoCo's default visible groups (0, 1, 2).
SILHOUETTE_GROUP = 5
#: Its materials (name -> rgba): HRP-2's blue covers, the dark visor, black lenses, amber fingers.
SILHOUETTE_RGBA = {
    "cover": "0.2 0.35 0.7 1",
    "visor": "0.12 0.14 0.2 1",
    "lens": "0.02 0.02 0.03 1",
    "finger": "0.95 0.6 0.1 1",
}
#: Camera window radius [m] by camera: the wide camera's lens is the larger.
WINDOW_RADIUS_M = {"wide": 0.016, "narrow_left": 0.011, "narrow_right": 0.011}
WINDOW_DEPTH_M = 0.006  # the lens barrel's length along the view axis (x of HEAD_LINK1)


def _box(name: str, lo, hi, material: str) -> Geom:
    return _silhouette(box_from_bbox(name, lo, hi, material))


def _silhouette(g: Geom) -> Geom:
    return Geom(g.name, g.kind, g.pos_m, g.size_m, axis=g.axis, material=g.material, collide=False,
                visual_class="silhouette")


def chest_geoms(params: dict) -> list[Geom]:
    """CHEST_LINK1: the chest block, a blue front plate, shoulder yokes and the backpack (the batteries' and
    computers' box behind, to the mesh bbox's back)."""
    lo, hi = bbox(params, "CHEST_LINK1")
    back, front, half_y, bottom, top = lo[0], hi[0], hi[1], lo[2], hi[2]
    return [
        _box("chest_core", (-0.09, -0.13, bottom), (front - 0.015, 0.13, top - 0.02), "trunk"),
        _box("chest_plate", (front - 0.02, -0.11, 0.07), (front, 0.11, top - 0.04), "cover"),
        _box("chest_shoulders", (-0.07, -half_y, top - 0.11), (0.08, half_y, top - 0.03), "trunk"),
        _box("chest_backpack", (back, -0.115, bottom + 0.05), (-0.09, 0.115, top - 0.03), "cover"),
    ]


def head_geoms(params: dict) -> list[Geom]:
    """HEAD_LINK1: the helmet, ear pods, a dark visor and one window per head camera (at the camera's y, z,
    just behind its optical centre)."""
    lo, hi = bbox(params, "HEAD_LINK1")
    front = min(pos[0] for pos, _, _ in CAMERAS.values()) - WINDOW_DEPTH_M / 2 - 0.001
    out = [
        _box("head_shell", (lo[0] + 0.05, lo[1] + 0.01, lo[2] + 0.01), (front - 0.01, hi[1] - 0.01, hi[2] - 0.01),
             "head"),
        _box("head_back", (lo[0], -0.07, lo[2] + 0.04), (lo[0] + 0.05, 0.07, hi[2] - 0.04), "cover"),
        _box("head_visor", (front - 0.012, -0.09, 0.07), (front - WINDOW_DEPTH_M, 0.09, 0.15), "visor"),
        _silhouette(Geom("head_ears", "cylinder", (-0.02, 0.0, 0.11), (0.035, hi[1]), axis="y", material="cover")),
    ]
    for name, (pos, _, _) in CAMERAS.items():
        out.append(_silhouette(Geom(f"window_{name}", "cylinder", (front - WINDOW_DEPTH_M / 2, pos[1], pos[2]),
                                    (WINDOW_RADIUS_M[name], WINDOW_DEPTH_M / 2), axis="x", material="lens")))
    return out


def hand_geoms(params: dict, side: str) -> list[Geom]:
    """<side>_LINK5: the wrist, the palm and the fixed finger (the jaw the can is pressed against), amber."""
    lo, hi = bbox(params, f"{side}_LINK5")
    prefix = side.lower()
    pz = gripper_pivot(params, side)[2]
    face_x = gripper_fixed_jaw_face_x(params, side)
    bottom = pz - FIXED_JAW_BOTTOM_BELOW_PIVOT_M
    return [
        _silhouette(Geom(f"{prefix}_wrist", "cylinder", (0.008, 0.0, hi[2] - 0.012), (0.042, 0.012),
                         material="joint")),
        _box(f"{prefix}_palm_cover", (lo[0], lo[1], pz + 0.005), (hi[0], hi[1], hi[2] - 0.024), "limb"),
        _box(f"{prefix}_fixed_finger", (face_x - FIXED_JAW_THICKNESS_M, -FINGER_WIDTH_M / 2, bottom),
             (face_x, FINGER_WIDTH_M / 2, pz + 0.005), "finger"),
    ]


def finger_geoms(side: str) -> list[Geom]:
    """<side>_LINK6: the moving finger from its pivot to the fingertip pad, amber like the fixed one."""
    prefix = side.lower()
    half = FINGER_PAD_DEPTH_M / 2
    return [
        _box(f"{prefix}_moving_finger", (-0.001, -FINGER_WIDTH_M / 2 + 0.004, -2 * half), (0.007,
             FINGER_WIDTH_M / 2 - 0.004, 0.008), "finger"),
        _silhouette(Geom(f"{prefix}_fingertip", "capsule", (0.0, 0.0, -FINGER_PAD_DEPTH_M),
                         (FINGER_PAD_RADIUS_M, FINGER_WIDTH_M / 2), axis="y", material="finger")),
    ]


def silhouette(params: dict) -> dict[str, list[Geom]]:
    """The silhouette's geoms by link; a link not named here is drawn by its collision shapes."""
    out = {"CHEST_LINK1": chest_geoms(params), "HEAD_LINK1": head_geoms(params)}
    for side in ("RARM", "LARM"):
        out[f"{side}_LINK5"] = hand_geoms(params, side)
        out[f"{side}_LINK6"] = finger_geoms(side)
    return out
