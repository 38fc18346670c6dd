"""Toe-heel contact of one stepping foot: phases (i)-(v), COP offset and pitch offset ([MLC] Sec. III-C 1))."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.layer import Params
from controller.interpolation.hoff_arbib import min_jerk

__all__ = ["PHASE_NAMES", "ToeHeelParams", "cop_offset_x", "foot_pitch_offset", "min_jerk", "phase_boundaries_s"]

#: (i) initial sole contact, (ii) COP sole -> toe, (iii) toe -> heel, (iv) heel -> sole, (v) final sole contact.
PHASE_NAMES = ("sole0", "sole2toe", "toe2heel", "heel2sole", "sole1")


@dataclass(frozen=True)
class ToeHeelParams(Params):
    """Phase lengths as fractions of the step time (they sum to 1) and the toe / heel edges of the sole.

    Sign convention (sole frame, x forward): `foot_pitch_offset > 0` is toe-off (the foot rotates about
    its toe edge, heel up, R = R_sole Ry(+theta)); `< 0` is heel contact (rotation about the heel edge,
    toes up). The defaults are those of Fig. 4 of [MLC] (1.0 s step: 0.05 / 0.25 / 0.4 / 0.25 / 0.05 s).
    """

    sole0_ratio: float = field(default=0.05, metadata={"unit": "-", "min": 0.0, "max": 1.0})  # (i)
    sole2toe_ratio: float = field(default=0.25, metadata={"unit": "-", "min": 0.0, "max": 1.0})  # (ii)
    toe2heel_ratio: float = field(default=0.40, metadata={"unit": "-", "min": 0.0, "max": 1.0})  # (iii)
    heel2sole_ratio: float = field(default=0.25, metadata={"unit": "-", "min": 0.0, "max": 1.0})  # (iv)
    sole1_ratio: float = field(default=0.05, metadata={"unit": "-", "min": 0.0, "max": 1.0})  # (v)
    # toe edge in the sole frame: COP target in (ii)/(iii) and pivot of the toe-off rotation [m]
    toe_offset_x_m: float = field(default=0.137, metadata={"unit": "m", "min": 0.0, "max": 0.5})
    # heel edge in the sole frame: COP target in (iii)/(iv) and pivot of the heel-contact rotation [m]
    heel_offset_x_m: float = field(default=-0.10, metadata={"unit": "m", "min": -0.5, "max": 0.0})
    # move the stepping foot's COP default -> toe -> heel -> default (hrpsys use_toe_heel_transition)
    use_cop_transition: bool = field(default=False, metadata={"unit": "-"})

    def validate(self) -> None:
        super().validate()
        total = sum(self.ratios)
        if abs(total - 1.0) > 1e-9:
            raise InvalidCommand(f"ToeHeelParams phase ratios {self.ratios} sum to {total}; they must sum to 1")

    @property
    def ratios(self) -> tuple[float, float, float, float, float]:
        return (self.sole0_ratio, self.sole2toe_ratio, self.toe2heel_ratio, self.heel2sole_ratio, self.sole1_ratio)


def phase_boundaries_s(step_time_s: float, params: ToeHeelParams, backward: bool = False) -> np.ndarray:
    """(6,) start of each phase and end of the last [s]; for a backward step the phases run (v) -> (i)."""
    ratios = params.ratios[::-1] if backward else params.ratios
    return step_time_s * np.concatenate([[0.0], np.cumsum(ratios)])


def _piecewise(t_s, step_time_s: float, params: ToeHeelParams, knots: np.ndarray, backward: bool, smooth: bool):
    """Value at the phase boundaries `knots` (6,) of the forward profile, linear or min-jerk inside each phase."""
    t = np.asarray(t_s, dtype=float)
    if backward:  # the reversed phase order is the forward profile played backwards in time
        t = step_time_s - t
    bounds = phase_boundaries_s(step_time_s, params)
    k = np.clip(np.searchsorted(bounds, t, side="right") - 1, 0, 4)
    length = bounds[k + 1] - bounds[k]
    s = np.divide(t - bounds[k], length, out=np.ones_like(t), where=length > 0.0)
    s = np.clip(s, 0.0, 1.0)
    if smooth:
        s = min_jerk(s)
    return knots[k] + (knots[k + 1] - knots[k]) * s


def cop_offset_x(t_s, step_time_s: float, params: ToeHeelParams, backward: bool = False):
    """COP offset of the stepping foot along its sole x at step time `t_s` [m] (linear in each phase).

    (i) 0, (ii) 0 -> toe, (iii) toe -> heel, (iv) heel -> 0, (v) 0. [MLC]'s text names (i), (iii), (v) for
    the three ramps but defines (ii)-(iv) as the COP transitions; the definitions are followed here.
    """
    knots = np.array([0.0, 0.0, params.toe_offset_x_m, params.heel_offset_x_m, 0.0, 0.0])
    return _piecewise(t_s, step_time_s, params, knots, backward, smooth=False)


def foot_pitch_offset(t_s, step_time_s: float, toe_angle_rad: float, heel_angle_rad: float,
                      params: ToeHeelParams, backward: bool = False):
    """Pitch offset of the stepping foot [rad], Hoff-Arbib (min-jerk) in each phase.

    (i) 0, (ii) 0 -> +toe, (iii) +toe -> -heel, (iv) -heel -> 0, (v) 0 (toe_angle, heel_angle >= 0).
    """
    knots = np.array([0.0, 0.0, toe_angle_rad, -heel_angle_rad, 0.0, 0.0])
    return _piecewise(t_s, step_time_s, params, knots, backward, smooth=True)
