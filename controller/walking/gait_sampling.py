"""The walking plan's samples: its parameters, the segments it is cut into, and their vectorised sampling (foot
poses, toe-heel, the Eq. 4 reference ZMP), as GaitGenerator and its stop from rest build them."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.layer import Params
from controller.interpolation.hoff_arbib import min_jerk
from controller.walking.footsteps import Footstep, other_leg
from controller.walking.swing_trajectory import ORBIT_TYPES, swing_position, swing_rpy
from controller.walking.toe_heel import ToeHeelParams, cop_offset_x, foot_pitch_offset

RIGHT, LEFT = 0, 1  # foot index in the (2, ...) arrays
SUPPORT_NAMES = ("rleg", "lleg", "both")
BOTH = 2  # support index of a double support
#: [s] the final double support of a stop from rest: the ZMP (and the COG with it) moves to the feet's middle
REST_STOP_DOUBLE_SUPPORT_S = 2.0


@dataclass(frozen=True)
class GaitParams(Params):
    """Timing and ZMP of the walking plan (hrpsys GaitGenerator defaults)."""

    # ZMP moves foot to foot over the last `after` and the first `before` fraction of the step times
    double_support_ratio_before: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    double_support_ratio_after: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    orbit_type: str = field(default="cycloid", metadata={"choices": ORBIT_TYPES})
    # hrpsys default_zmp_offsets: each foot's COP in its sole frame [m]
    rleg_zmp_offset_x_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    rleg_zmp_offset_y_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    lleg_zmp_offset_x_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    lleg_zmp_offset_y_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    # duration of the final double support that brings the ZMP back to the feet mid-coords [s]
    final_double_support_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.05, "max": 10.0})
    preview_time_s: float = field(default=1.6, metadata={"unit": "s", "min": 0.0, "max": 10.0})  # ZMP preview


@dataclass
class Segment:
    """One footstep's share of the plan: "start" (initial double support), "step", or "end"."""

    kind: str
    index: int  # footstep index (len(footsteps) for "end")
    duration_s: float
    n_ticks: int
    start_tick: int  # absolute tick of its first sample
    q_start: np.ndarray  # (2, 6) feet (x, y, z, roll, pitch, yaw) at its start
    q_end: np.ndarray | None = None
    # the GaitParams the segment was planned with: a parameter change applies to the segments planned
    # after it, a replan that resamples this segment keeps its timing (no jump of the ZMP mid-step)
    params: GaitParams | None = None


def rpy_matrices(rpy: np.ndarray) -> np.ndarray:
    """(n, 3, 3) R = Rz(yaw) Ry(pitch) Rx(roll) for (n, 3) roll-pitch-yaw [rad]."""
    r, p, y = rpy[:, 0], rpy[:, 1], rpy[:, 2]
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.stack([
        np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=-1),
        np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=-1),
        np.stack([-sp, cp * sr, cp * cr], axis=-1),
    ], axis=1)


def ry(theta: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    z, o = np.zeros_like(theta), np.ones_like(theta)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], axis=1)


def compose_planar(a: tuple, b: tuple) -> tuple[float, float, float]:
    """Planar pose a composed with b: (x [m], y [m], yaw [rad])."""
    c, s = np.cos(a[2]), np.sin(a[2])
    yaw = (a[2] + b[2] + np.pi) % (2.0 * np.pi) - np.pi
    return (float(a[0] + c * b[0] - s * b[1]), float(a[1] + s * b[0] + c * b[1]), float(yaw))


def relative_planar(a: tuple, b: tuple) -> tuple[float, float, float]:
    """b in the frame of a: (x [m], y [m], yaw [rad])."""
    c, s = np.cos(a[2]), np.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    yaw = (b[2] - a[2] + np.pi) % (2.0 * np.pi) - np.pi
    return (float(c * dx + s * dy), float(-s * dx + c * dy), float(yaw))


def q_of(step: Footstep) -> np.ndarray:
    """(6,) the footstep's (x, y, z [m], roll, pitch, yaw [rad])."""
    return np.array([step.x, step.y, step.z, step.roll, step.pitch, step.yaw])



def zmp_offsets(params: GaitParams) -> np.ndarray:
    """(2, 3) each foot's COP in its sole frame [m] (right, left)."""
    p = params
    return np.array([[p.rleg_zmp_offset_x_m, p.rleg_zmp_offset_y_m, 0.0],
                     [p.lleg_zmp_offset_x_m, p.lleg_zmp_offset_y_m, 0.0]])


def n_ticks(duration_s: float, dt_s: float) -> int:
    """How many ticks of `dt_s` [s] last `duration_s` [s]; InvalidCommand unless a whole number."""
    n = int(round(duration_s / dt_s))
    if n < 1 or abs(n * dt_s - duration_s) > 1e-9:
        raise InvalidCommand(f"step time {duration_s} s is not a whole number of ticks of {dt_s} s; "
                             f"use e.g. {max(n, 1) * dt_s:.6g} s")
    return n


def left_weight(footsteps: Sequence[Footstep], k: int) -> float:
    """Eq. 4 weight of the left foot while footstep k is stepped on (support = the other leg)."""
    return 1.0 if other_leg(footsteps[k].leg) == "lleg" else 0.0


def sample_segment(seg: Segment, footsteps: Sequence[Footstep], params: GaitParams, toe_heel: ToeHeelParams,
                   zmp_offsets_m: np.ndarray, dt_s: float) -> dict[str, np.ndarray]:
    """Vectorised samples of one segment at local times dt, 2 dt, ..., duration (the last one exact); `params`: the
    generator's, for a segment planned without its own. Sets seg.q_end."""
    n, T = seg.n_ticks, seg.duration_s
    t = np.arange(1, n + 1) * dt_s
    t[-1] = T
    q = seg.q_start.copy()  # (2, 6)
    p = np.repeat(q[:, None, :3], n, axis=1)  # (2, n, 3)
    R = np.repeat(rpy_matrices(q[:, 3:])[:, None], n, axis=1)  # (2, n, 3, 3)
    cop = np.zeros((n, 2))
    pitch = np.zeros((n, 2))
    support = np.full(n, BOTH, dtype=np.int8)
    R_flat = R.copy()  # sole orientation without the toe-heel pitch (COP frame)
    p_flat = p.copy()
    steps, k = footsteps, seg.index
    gp = seg.params or params
    ds_b, ds_a = gp.double_support_ratio_before, gp.double_support_ratio_after
    if seg.kind == "start":
        w = left_weight(steps, 1) if len(steps) > 1 else 0.5
        r = 0.5 + (w - 0.5) * t / T
    elif seg.kind == "end":
        r_start = left_weight(steps, k - 1) if k > 1 else 0.5
        r = r_start + (0.5 - r_start) * t / T
    else:
        fs = steps[k]
        sw = LEFT if fs.leg == "lleg" else RIGHT
        w = left_weight(steps, k)
        r_start = 0.5 * (left_weight(steps, k - 1) + w) if k > 1 else w
        r_end = 0.5 * (w + left_weight(steps, k + 1)) if k + 1 < len(steps) else w
        tb, ta = ds_b * T, T - ds_a * T
        r = np.full(n, w)
        if tb > 0.0:
            r = np.where(t < tb, r_start + (w - r_start) * t / tb, r)
        if ta < T:
            r = np.where(t > ta, w + (r_end - w) * (t - ta) / (T - ta), r)
        support[(t > tb) & (t < ta)] = 1 - sw
        q_dst = q_of(fs)
        s = np.clip((t - tb) / max(ta - tb, 1e-12), 0.0, 1.0)
        p_sw = swing_position(s, q[sw, :3], q_dst[:3], fs.step_height_m, gp.orbit_type)
        rpy_sw = swing_rpy(s, q[sw, 3:], q_dst[3:])
        R_sw = rpy_matrices(rpy_sw)
        p_flat[sw], R_flat[sw] = p_sw, R_sw
        th = toe_heel
        backward = float((R[sw, 0].T @ (q_dst[:3] - q[sw, :3]))[0]) < -1e-6
        if th.use_cop_transition:
            cop[:, sw] = cop_offset_x(t, T, th, backward)
        if fs.toe_angle_rad > 0.0 or fs.heel_angle_rad > 0.0:
            theta = foot_pitch_offset(t, T, fs.toe_angle_rad, fs.heel_angle_rad, th, backward)
            pitch[:, sw] = theta
            R_pitched = R_sw @ ry(theta)
            pivot = np.zeros((n, 3))
            pivot[:, 0] = np.where(theta > 0.0, th.toe_offset_x_m, th.heel_offset_x_m)
            p_sw = p_sw + np.einsum("nij,nj->ni", R_sw - R_pitched, pivot)
            R_sw = R_pitched
        p[sw], R[sw] = p_sw, R_sw
        q[sw] = q_dst
    cop_local = np.repeat(zmp_offsets_m[None], n, axis=0)  # (n, 2, 3)
    cop_local[:, :, 0] += cop
    p_cop = p_flat + np.einsum("fnij,nfj->fni", R_flat, cop_local)  # (2, n, 3)
    zmp = (1.0 - r)[:, None] * p_cop[RIGHT] + r[:, None] * p_cop[LEFT]
    seg.q_end = q
    return {"zmp": zmp, "p": p, "R": R, "r": r, "cop": cop, "pitch": pitch, "support": support,
            "index": np.full(n, k, dtype=np.int32)}


def rest_stop(rest_from: tuple, zmp_world_xy: Sequence[float], swing_foot_loaded: bool, landing_speed_m_s: float,
              min_landing_time_s: float, step_time_s: float, zmp_offsets_m: np.ndarray,
              dt_s: float) -> tuple[list[Footstep], list[dict[str, np.ndarray]], float]:
    """GaitGenerator.stop_from_rest's footsteps, sample blocks (the swing foot's landing if on one foot, then the
    final double support) and landing time [s], from `rest_from`: the feet (2, 3), (2, 3, 3), the support index
    and the footstep being stepped where the plan is held."""
    p, R, support, dst = rest_from
    p, R = p.copy(), R.copy()  # (2, 3), (2, 3, 3)
    zmp0 = np.array([float(zmp_world_xy[0]), float(zmp_world_xy[1]), 0.0])
    zmp0[2] = 0.5 * (p[RIGHT, 2] + p[LEFT, 2]) if support == BOTH or swing_foot_loaded else p[support, 2]
    legs = ("rleg", "lleg")
    stand = support if support != BOTH else RIGHT
    steps = [Footstep(legs[stand], *(float(v) for v in p[stand]),
                      yaw=float(np.arctan2(R[stand, 1, 0], R[stand, 0, 0])), step_time_s=step_time_s)]
    blocks = []
    landing_s = 0.0
    if support != BOTH:
        sw = 1 - support
        if dst.leg != legs[sw]:  # (the footstep being stepped is the swing foot's) else land it level
            dst = Footstep(legs[sw], float(p[sw, 0]), float(p[sw, 1]), float(p[support, 2]))
        yaw_now = float(np.arctan2(R[sw, 1, 0], R[sw, 0, 0]))
        landing = Footstep(dst.leg, float(p[sw, 0]), float(p[sw, 1]), dst.z, yaw_now, dst.roll, dst.pitch,
                           step_time_s=step_time_s)
        height = float(p[sw, 2] - landing.z)
        n = n_ticks(dt_s * max(1, int(np.ceil(max(min_landing_time_s, abs(height) / landing_speed_m_s) / dt_s))), dt_s)
        s_mj = min_jerk(np.arange(1, n + 1) / n)
        landing_s = n * dt_s
        q_dst = q_of(landing)
        rpy_now = np.array([float(np.arctan2(R[sw, 2, 1], R[sw, 2, 2])), float(-np.arcsin(R[sw, 2, 0])), yaw_now])
        rpy_sw = rpy_now[None] + s_mj[:, None] * (q_dst[3:] - rpy_now)[None]
        pp = np.repeat(p[:, None], n, axis=1)
        RR = np.repeat(R[:, None], n, axis=1)
        pp[sw] = p[sw][None] + s_mj[:, None] * (q_dst[:3] - p[sw])[None]
        RR[sw] = rpy_matrices(rpy_sw)
        landing_support = BOTH if swing_foot_loaded else support
        blocks.append({"zmp": np.repeat(zmp0[None], n, axis=0), "p": pp, "R": RR,
                       "r": np.full(n, float(support == LEFT)), "cop": np.zeros((n, 2)), "pitch": np.zeros((n, 2)),
                       "support": np.full(n, landing_support, dtype=np.int8),
                       "index": np.full(n, 1, dtype=np.int32)})
        p[sw], R[sw] = q_dst[:3], rpy_matrices(q_dst[None, 3:])[0]
        steps.append(landing)
    n = n_ticks(REST_STOP_DOUBLE_SUPPORT_S, dt_s)
    t = min_jerk(np.arange(1, n + 1) / n)[:, None]
    mid = 0.5 * (p[RIGHT] + R[RIGHT] @ zmp_offsets_m[RIGHT] + p[LEFT] + R[LEFT] @ zmp_offsets_m[LEFT])
    blocks.append({"zmp": zmp0[None] + t * (mid - zmp0)[None], "p": np.repeat(p[:, None], n, axis=1),
                   "R": np.repeat(R[:, None], n, axis=1), "r": np.full(n, 0.5), "cop": np.zeros((n, 2)),
                   "pitch": np.zeros((n, 2)), "support": np.full(n, BOTH, dtype=np.int8),
                   "index": np.full(n, len(steps), dtype=np.int32)})
    return steps, blocks, landing_s
