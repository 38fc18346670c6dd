"""The /api/state document built from a published snapshot (its schema: app.console.state), in the robot's
service because OperatorService.state caches it per snapshot; the console adds its lock and journal."""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import numpy as np

from app.service.host import Published
from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    distance_to_polygon_edge,
    support_polygon,
)
from controller.core.layer import plain
from controller.kinematics.rotations import matrix_to_rpy, quat_wxyz_to_matrix
from robot.names import FORCE_SENSOR_NAMES, JOINT_NAMES
from robot.sensors import is_fallen


def _yaw_rad(R) -> float:
    """The heading [rad] of the rotation matrix R (its x axis in the horizontal plane)."""
    R = np.asarray(R, dtype=float)
    return float(math.atan2(R[1, 0], R[0, 0]))


def support_edge_mm(snap) -> float | None:
    """Distance [mm] from the reference capture point to the edge of the support polygon of the soles in contact
    (the planned ones): the error at which the actual capture point would leave the support, in the worst
    direction. None without a gait reference or a Stabilizer."""
    gait = getattr(getattr(snap, "reference", None), "gait", None)
    st = snap.layers.get("st")
    if gait is None or st is None or getattr(st, "cp_ref", None) is None:
        return None
    feet = [((p[0], p[1], _yaw_rad(R)), rect) for p, R, rect, on in (
        (gait.p_rsole_world, gait.R_rsole_world, HRP2_RIGHT_SOLE, gait.contact[0]),
        (gait.p_lsole_world, gait.R_lsole_world, HRP2_LEFT_SOLE, gait.contact[1])) if on]
    if not feet:
        return None
    return 1e3 * max(0.0, distance_to_polygon_edge(st.cp_ref, support_polygon(feet)))


_RFOOT, _LFOOT = FORCE_SENSOR_NAMES.index("rfsensor"), FORCE_SENSOR_NAMES.index("lfsensor")


def jsonable(value: Any) -> Any:
    """Numpy arrays and scalars to lists and floats; NaN and infinities to None; dataclasses to dicts."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        f = float(value)
        return f if math.isfinite(f) else None
    if value is None or isinstance(value, str):
        return value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return jsonable(plain(value))
    return str(value)


def _deg(a) -> list[float]:
    return [round(v, 4) for v in np.rad2deg(np.asarray(a, dtype=float)).tolist()]


def _rounded(a, digits: int) -> list[float]:
    return [round(v, digits) for v in np.asarray(a, dtype=float).tolist()]


def _xy(v) -> list[float]:
    return [round(float(c), 6) for c in (v if v is not None else (0.0, 0.0))[:2]]


def _support_edge_m(snap) -> float | None:
    """How far [m] the reference CP is inside the planned support polygon (the 3D view's plot computes it so)."""
    edge = support_edge_mm(snap)
    return None if edge is None else round(edge / 1e3, 6)


def state_document(pub: Published) -> dict[str, Any]:
    """The GET /api/state contract (see StateDocument for every field, its unit and meaning), in plain Python
    types already (floats from tolist, statuses through `plain`): `state_json` encodes it without a walk over
    every value unless a NaN or an infinity needs turning into null."""
    snap = pub.snapshot
    truth = pub.truth
    rpy_truth = matrix_to_rpy(quat_wxyz_to_matrix(np.asarray(truth.base_quat_wxyz, dtype=float)))
    cmd, meas, seq = (_deg(snap.q_cmd_rad), _deg(snap.q_meas_rad), _deg(snap.q_seq_rad))
    joints = {n: {"cmd_deg": cmd[i], "meas_deg": meas[i], "seq_deg": seq[i]} for i, n in enumerate(JOINT_NAMES)}
    layers = snap.layers
    abc, st, es = layers.get("abc"), layers.get("st"), layers.get("es")
    safety = snap.safety
    flag_rose_at = getattr(st, "flag_rose_at", None)
    cp_threshold_m = float(getattr(st, "cp_threshold_m", 0.0))
    layer_docs = {}
    for name, status in layers.items():
        d = plain(status)
        d["tick_ms"] = round(float(snap.layer_tick_ms.get(name, 0.0)), 5)
        layer_docs[name] = d
    return {
        "time": round(float(snap.time_s), 6),
        "tick": int(snap.tick),
        "fallen": bool(is_fallen(truth) or safety.fall is not None),
        "base": {"pos": _rounded(truth.base_pos_world, 5), "rpy_deg": _deg(rpy_truth),
                 "linvel": _rounded(truth.base_linvel_world, 5), "source": "simulation"},
        "estimate": {"rpy_deg": _deg(snap.base_rpy_est_rad), "source": "kf"},
        "joints": joints,
        "cog": _rounded(snap.cog_world, 5),
        "zmp": _rounded(snap.zmp_world, 5),
        "foot_forces_n": {"rleg": round(float(snap.wrenches_ext[_RFOOT][2]), 3),
                          "lleg": round(float(snap.wrenches_ext[_LFOOT][2]), 3)},
        "walking": bool(getattr(abc, "walking", False)),
        "support": str(getattr(abc, "support", "both")),
        "capture_point": {"ref": _xy(getattr(st, "cp_ref", None)), "act": _xy(getattr(st, "cp_act", None)),
                          "error": _xy(getattr(st, "cp_error", None)),
                          "error_norm": round(float(getattr(st, "cp_error_norm", 0.0)), 6),
                          "cp_threshold_m": cp_threshold_m,
                          "support_edge_m": _support_edge_m(snap),
                          "threshold": cp_threshold_m},  # deprecated name of cp_threshold_m
        "emergency": {
            "hard_stop": safety.hard_stop, "hard_stop_reason": safety.hard_stop_reason,
            "hard_stop_stopping": safety.hard_stop_stopping, "fault": safety.fault,
            "fall": safety.fall,
            "flag": bool(getattr(st, "emergency", False)),
            "flag_rise_time": flag_rose_at,  # deprecated name of flag_rose_at
            "flag_rose_at": flag_rose_at,
            "motion_stop": bool(getattr(es, "stopped", False)),
            "motion_stop_reason": getattr(es, "reason", None),
            "motion_stop_time": getattr(es, "flag_time", None),
            "motion_stop_cp_error_m": getattr(es, "cp_error_m", None),
            "flag_cp_error_m": getattr(st, "flag_cp_error_m", None),
            "walking_stop": bool(getattr(abc, "walking_stop", False)),
            "walk_cut": getattr(abc, "walk_cut", None),  # why the last walk ended early (the CP), or None
            "stabilizer_stop": st is not None and not st.active},
        "layers": layer_docs,
        "chain": pub.chain,
        "speed": pub.speed,
        "scene": pub.scene,
        "loop_ms": round(float(snap.loop_ms), 4),
        "loop": {"lateness_p99_ms": pub.timing.lateness_p99_ms, "lateness_max_ms": pub.timing.lateness_max_ms,
                 "speed_last": pub.timing.speed_last},
        "operation": _operation(layers.get("op")),
        "runs": [r.to_dict() for r in pub.runs],
        "operator_acks": {p: {"seq": a.seq, "tick": a.tick, "time_s": a.time_s, "ignored": a.ignored}
                          for p, a in pub.setpoint_acks.items()},
    }


def _operation(status) -> dict[str, Any] | None:
    """The operation layer's status per operational point (its own to_dict), or None without the layer."""
    if status is None:
        return None
    to_dict = getattr(status, "to_dict", None)
    return jsonable(to_dict() if callable(to_dict) else plain(status))


def state_json(pub: Published) -> tuple[dict[str, Any], bytes]:
    """The state document and its JSON encoding (non-finite numbers as null)."""
    doc = state_document(pub)
    try:
        body = json.dumps(doc, separators=(",", ":"), allow_nan=False)
    except ValueError:  # a NaN or an infinity somewhere (a fault): the slow walk that nulls them
        doc = jsonable(doc)
        body = json.dumps(doc, separators=(",", ":"), allow_nan=False)
    return doc, body.encode()
