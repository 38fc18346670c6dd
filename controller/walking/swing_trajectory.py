"""Swing-foot position and orientation between two footholds over the swing time (cycloid, rectangle,
trapezoid)."""

from __future__ import annotations

import numpy as np

from controller.interpolation.hoff_arbib import min_jerk

__all__ = ["ORBIT_TYPES", "swing_position", "swing_rpy"]

ORBIT_TYPES = ("cycloid", "rectangle", "trapezoid")
#: share of the swing over which the trapezoid orbit's horizontal speed ramps up, and again down
TRAPEZOID_RAMP = 0.25


def _cycloid(s: np.ndarray, p_src: np.ndarray, p_dst: np.ndarray, step_height_m: float) -> np.ndarray:
    """hrpsys CYCLOID: horizontal ratio (2 pi s - sin 2 pi s) / 2 pi, height h (1 - cos 2 pi s) / 2."""
    two_pi_s = 2.0 * np.pi * s
    ratio = np.where(s >= 1.0, 1.0, (two_pi_s - np.sin(two_pi_s)) / (2.0 * np.pi))
    lift = np.where((s <= 0.0) | (s >= 1.0), 0.0, 0.5 * step_height_m * (1.0 - np.cos(two_pi_s)))
    p = p_src + (p_dst - p_src) * ratio[:, None]
    p[:, 2] += lift
    return p


def _rectangle(s: np.ndarray, p_src: np.ndarray, p_dst: np.ndarray, step_height_m: float) -> np.ndarray:
    """Lift vertically, move horizontally, lower vertically; min-jerk on each leg, time shared by length."""
    z_top = max(p_src[2], p_dst[2]) + step_height_m
    lengths = np.array([z_top - p_src[2], np.linalg.norm(p_dst[:2] - p_src[:2]), z_top - p_dst[2]])
    total = lengths.sum()
    p = np.repeat(p_src[None, :], s.size, axis=0)
    if total <= 0.0:
        return p
    edges = np.concatenate([[0.0], np.cumsum(lengths) / total])
    ramps = [np.where(lengths[k] > 0.0, min_jerk((s - edges[k]) / max(edges[k + 1] - edges[k], 1e-300)),
                      (s >= edges[k + 1]).astype(float)) for k in range(3)]
    p[:, 2] = p_src[2] + (z_top - p_src[2]) * ramps[0] - (z_top - p_dst[2]) * ramps[2]
    p[:, :2] = p_src[:2] + (p_dst[:2] - p_src[:2]) * ramps[1][:, None]
    end = s >= 1.0
    p[end] = p_dst
    return p


def _trapezoid(s: np.ndarray, p_src: np.ndarray, p_dst: np.ndarray, step_height_m: float) -> np.ndarray:
    """The cycloid's height with a horizontal speed that ramps up (raised cosine) over the first TRAPEZOID_RAMP of
    the swing, stays constant, and ramps down over the last: its peak is 1 / (1 - ramp) = 4/3 of the mean speed
    against the cycloid's 2, so a step that must be fast (the emergency step) asks the joints less."""
    a = TRAPEZOID_RAMP
    v = 1.0 / (1.0 - a)  # cruise speed of the ratio [1 / swing]
    # ramp up: the speed v (1 - cos(pi s / a)) / 2, integrated
    up = 0.5 * v * (s - (a / np.pi) * np.sin(np.pi * s / a))
    cruise = 0.5 * v * a + v * (s - a)
    ratio = np.where(s < a, up, np.where(s <= 1.0 - a, cruise, 1.0 - 0.5 * v * ((1.0 - s) - (a / np.pi)
                                                                                 * np.sin(np.pi * (1.0 - s) / a))))
    ratio = np.where(s >= 1.0, 1.0, ratio)
    lift = np.where((s <= 0.0) | (s >= 1.0), 0.0, 0.5 * step_height_m * (1.0 - np.cos(2.0 * np.pi * s)))
    p = p_src + (p_dst - p_src) * ratio[:, None]
    p[:, 2] += lift
    return p


def swing_position(s, p_src, p_dst, step_height_m: float, orbit_type: str = "cycloid") -> np.ndarray:
    """(n, 3) swing-foot sole position [m] at swing ratios `s` (n,) in [0, 1]; zero velocity at both ends.

    The sole is exactly at `p_src` for s <= 0 and exactly at `p_dst` for s >= 1. The height above the
    straight line src -> dst peaks at `step_height_m` (cycloid, at s = 0.5; rectangle: above the higher end).
    """
    s = np.clip(np.atleast_1d(np.asarray(s, dtype=float)), 0.0, 1.0)
    p_src = np.asarray(p_src, dtype=float)
    p_dst = np.asarray(p_dst, dtype=float)
    if orbit_type == "cycloid":
        return _cycloid(s, p_src, p_dst, step_height_m)
    if orbit_type == "rectangle":
        return _rectangle(s, p_src, p_dst, step_height_m)
    if orbit_type == "trapezoid":
        return _trapezoid(s, p_src, p_dst, step_height_m)
    raise ValueError(f"orbit_type {orbit_type!r}; valid: {list(ORBIT_TYPES)}")


def swing_rpy(s, rpy_src, rpy_dst) -> np.ndarray:
    """(n, 3) roll-pitch-yaw [rad] interpolated by min-jerk; the yaw takes the short way round."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    rpy_src = np.asarray(rpy_src, dtype=float)
    delta = np.asarray(rpy_dst, dtype=float) - rpy_src
    delta = (delta + np.pi) % (2.0 * np.pi) - np.pi
    return rpy_src + delta * min_jerk(s)[:, None]
