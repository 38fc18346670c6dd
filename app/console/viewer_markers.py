"""The 3D view's markers: the balance markers (COG, ZMP, capture points, support polygon, soles, planned
footsteps) and the operation layer's hand targets, built once and then only moved, shown or hidden, and a marker
per located object; with the floor geometry they are drawn from."""

from __future__ import annotations

import math

import numpy as np

from behaviors.perception.models import HELD
from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE, support_polygon
from controller.balance.leg_odometry import control_to_world
from controller.operation.targets import feet_frame, yaw_rotation

OP_TARGET_POINTS = ("rhand", "lhand")  # operational points whose target position is drawn (x, y, z in F)
MAX_FOOTSTEPS = 16  # planned footsteps drawn (fixed buffer: the handles are only updated, never rebuilt)
_FLOOR_LIFT_M = 0.002  # floor markers drawn this far above the sole plane so they are not hidden
_SOLES = {"rleg": HRP2_RIGHT_SOLE, "lleg": HRP2_LEFT_SOLE}


def yaw_of(R) -> float:
    """The heading [rad] of the rotation matrix R (its x axis in the horizontal plane)."""
    R = np.asarray(R, dtype=float)
    return float(math.atan2(R[1, 0], R[0, 0]))


def _closed_segments(xy: np.ndarray, z: float) -> np.ndarray:
    """(M, 2, 3) segments of the closed polygon through the (M, 2) points `xy` at height z."""
    p = np.column_stack([xy, np.full(len(xy), z)])
    return np.stack([p, np.roll(p, -1, axis=0)], axis=1)


def _padded(segments: np.ndarray, n: int) -> np.ndarray:
    """Exactly n segments: the extra slots repeat the last real one (drawn over it, so invisible)."""
    segments = segments[:n]
    if len(segments) < n:
        segments = np.concatenate([segments, np.repeat(segments[-1:], n - len(segments), axis=0)])
    return segments.astype(np.float32)


def footstep_rectangles(steps, z: float) -> np.ndarray:
    """(4 * len(steps), 2, 3) outline segments of footsteps given as {"leg", "pos": [3], "yaw"} [m, rad]."""
    segs = []
    for step in steps:
        rect = _SOLES.get(str(step.get("leg")), HRP2_RIGHT_SOLE)
        pos = np.asarray(step.get("pos", (0.0, 0.0, z)), dtype=float)
        corners = rect.corners_world((pos[0], pos[1], float(step.get("yaw", 0.0))))
        segs.append(_closed_segments(corners, (float(pos[2]) if len(pos) > 2 else z) + _FLOOR_LIFT_M))
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def ray_at_height(origin, direction, z_m: float) -> np.ndarray | None:
    """Where the ray origin + t direction (t > 0) crosses the horizontal plane z = z_m (world [m]); None when it
    runs parallel to it or away from it."""
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    if abs(d[2]) < 1e-9:
        return None
    t = (float(z_m) - o[2]) / d[2]
    return None if t <= 0 else o + t * d


class BalanceMarkers:
    """The balance markers and the hand targets in a viser scene: `handles` (name -> viser handle) are built once,
    then only moved, shown or hidden (`update`)."""

    def __init__(self, scene) -> None:
        m: dict = {}
        m["cog"] = scene.add_icosphere("/markers/cog", radius=0.03, color=(255, 140, 0), subdivisions=2,
                                       cast_shadow=False, receive_shadow=False)
        m["zmp"] = scene.add_cylinder("/markers/zmp", radius=0.02, height=0.004, color=(40, 200, 60),
                                      radial_segments=16, cast_shadow=False, receive_shadow=False)
        m["cp_ref"] = scene.add_icosphere("/markers/cp_ref", radius=0.015, color=(30, 110, 255), subdivisions=1,
                                          cast_shadow=False, receive_shadow=False)
        m["cp_act"] = scene.add_icosphere("/markers/cp_act", radius=0.015, color=(230, 30, 60), subdivisions=1,
                                          cast_shadow=False, receive_shadow=False)
        seg = np.zeros((1, 2, 3), dtype=np.float32)
        m["support"] = scene.add_line_segments("/markers/support_polygon", _padded(seg, 8), (255, 215, 0),
                                               thickness=0.004, visible=False)
        m["soles"] = scene.add_line_segments("/markers/soles", _padded(seg, 8), (90, 90, 110),
                                             thickness=0.003, visible=False)
        m["footsteps"] = scene.add_line_segments("/markers/footsteps", _padded(seg, 4 * MAX_FOOTSTEPS),
                                                 (0, 170, 200), thickness=0.003, visible=False)
        for point, color in zip(OP_TARGET_POINTS, ((200, 40, 200), (120, 40, 220)), strict=True):
            m[f"target_{point}"] = scene.add_icosphere(f"/markers/target_{point}", radius=0.025, color=color,
                                                       subdivisions=1, opacity=0.6, cast_shadow=False,
                                                       receive_shadow=False, visible=False)
        self.handles = m

    @staticmethod
    def _show(handle, visible: bool) -> None:
        if handle.visible != visible:
            handle.visible = visible

    def _place(self, handle, pos) -> None:
        p = np.asarray(pos, dtype=float)
        ok = p.shape == (3,) and bool(np.all(np.isfinite(p)))
        if ok:
            handle.position = p
        self._show(handle, ok)

    def update(self, snap) -> None:
        """The balance markers, computed in the controller's frame (the gait plan's), drawn in the world of leg
        odometry (`snap.odometry.world_from_control`) beside the robot drawn from the simulation: the plan's frame
        drifts from the world with the landings it never sees (19 mm after 1 m of walking), the odometry stays
        within about a millimetre."""
        m = self.handles
        odometry = getattr(snap, "odometry", None)
        wfc = None if odometry is None else odometry.world_from_control
        to_world = (lambda p: p) if wfc is None else (lambda p: np.asarray(control_to_world(wfc, p)))
        dyaw = 0.0 if wfc is None else float(wfc[3])
        gait = getattr(snap.reference, "gait", None)
        zmp = np.asarray(snap.zmp_world, dtype=float)
        if gait is not None:
            floor_z = 0.5 * (float(gait.p_rsole_world[2]) + float(gait.p_lsole_world[2]))
        else:
            floor_z = float(zmp[2]) if np.isfinite(zmp[2]) else 0.0
        self._place(m["cog"], to_world(np.asarray(snap.cog_world, dtype=float)))
        self._place(m["zmp"], to_world((zmp[0], zmp[1], floor_z + _FLOOR_LIFT_M)))
        st = snap.layers.get("st")
        for key in ("cp_ref", "cp_act"):
            xy = getattr(st, key, None)
            if xy is None:
                self._show(m[key], False)
            else:
                self._place(m[key], to_world((float(xy[0]), float(xy[1]), floor_z + 2 * _FLOOR_LIFT_M)))
        if gait is None:
            for key in ("support", "soles"):
                self._show(m[key], False)
        else:
            soles = [(to_world(p), yaw_of(R) + dyaw) for p, R in ((gait.p_rsole_world, gait.R_rsole_world),
                                                              (gait.p_lsole_world, gait.R_lsole_world))]
            feet = [((p[0], p[1], yaw), rect) for (p, yaw), rect in zip(soles, (HRP2_RIGHT_SOLE, HRP2_LEFT_SOLE),
                                                                        strict=True)]
            steps = [{"leg": leg, "pos": p, "yaw": yaw} for leg, (p, yaw) in zip(("rleg", "lleg"), soles, strict=True)]
            m["soles"].points = _padded(footstep_rectangles(steps, floor_z), 8)
            self._show(m["soles"], True)
            in_contact = [f for f, on in zip(feet, gait.contact, strict=True) if on]
            if in_contact:
                poly = support_polygon(in_contact)
                m["support"].points = _padded(_closed_segments(poly, floor_z + _FLOOR_LIFT_M), 8)
            self._show(m["support"], bool(in_contact))
        abc = snap.layers.get("abc")
        planned = [{"leg": f.leg, "pos": to_world(f.pos), "yaw": f.rpy[2] + dyaw}
                   for f in (abc.footsteps if abc is not None else ())]
        if planned:
            m["footsteps"].points = _padded(footstep_rectangles(planned[:MAX_FOOTSTEPS], floor_z),
                                            4 * MAX_FOOTSTEPS)
        self._show(m["footsteps"], bool(planned))
        self._update_targets(snap, gait, to_world)

    def _update_targets(self, snap, gait, to_world) -> None:
        """The operation layer's hand targets (x, y, z in the feet frame F) drawn in the world (`to_world`: a
        point of the controller's frame in the world)."""
        op = snap.layers.get("op")
        points = getattr(op, "points", None) or {}
        frame = None
        if gait is not None:
            frame = feet_frame(gait.p_rsole_world, gait.R_rsole_world, gait.p_lsole_world, gait.R_lsole_world)
        for point in OP_TARGET_POINTS:
            handle = self.handles[f"target_{point}"]
            status = points.get(point)
            target = getattr(status, "target", None)
            if frame is None or target is None:
                self._show(handle, False)
                continue
            origin, yaw = frame
            self._place(handle, to_world(origin + yaw_rotation(yaw) @ np.asarray(target[:3], dtype=float)))


class RecognitionMarkers:
    """A sphere and a label per located object; `shown` is object -> (sphere, label, (position, status) shown)."""

    def __init__(self, scene) -> None:
        self.scene = scene
        self.shown: dict[str, tuple] = {}

    def update(self, recognitions) -> None:
        """A marker and a label at each located object's position (the operator's correction once given); none
        for an object the robot holds (where it was taken from is out of date)."""
        scene = self.scene
        recognitions = {n: r for n, r in recognitions.items() if r.get("status") != HELD}
        for name in list(self.shown):
            if name not in recognitions:  # a reset forgot it, or the robot took it
                for handle in reversed(self.shown.pop(name)[:2]):
                    handle.remove()
        for name, rec in recognitions.items():
            pos = tuple(float(v) for v in rec.get("position_m", ()))
            if len(pos) != 3 or not all(math.isfinite(v) for v in pos):
                continue
            status = rec.get("status", "estimated")
            shown = self.shown.get(name)
            if shown is not None and shown[2] == (pos, status):
                continue
            if shown is not None:
                for handle in reversed(shown[:2]):
                    handle.remove()
            color = (40, 170, 60) if status != "estimated" else (255, 200, 0)
            sphere = scene.add_icosphere(f"/recognitions/{name}", radius=0.04, color=color, subdivisions=2,
                                         opacity=0.7, position=pos, cast_shadow=False, receive_shadow=False)
            sigma = rec.get("sigma_m") or [0.0, 0.0]
            label = scene.add_label(f"/recognitions/{name}/label",
                                    f"{name} ({status}, sigma {1e3 * math.hypot(*sigma[:2]):.0f} mm)",
                                    position=(0.0, 0.0, 0.1))
            self.shown[name] = (sphere, label, (pos, status))
