"""Fall detection from the robot's own sensors (KalmanFilter attitude, foot F/T sensors): the loop's
trigger for the safe stop when the robot has fallen or left the ground."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from controller.core.layer import Params
from controller.core.types import Estimate
from robot.names import FORCE_SENSOR_NAMES

_FEET = (FORCE_SENSOR_NAMES.index("rfsensor"), FORCE_SENSOR_NAMES.index("lfsensor"))


def tilt_rad(rpy_rad) -> float:
    """[rad] how far BODY's z axis is from the vertical for roll, pitch (, yaw) in a level frame: the fall's
    measure, and the waist point's limit on it."""
    roll, pitch = float(rpy_rad[0]), float(rpy_rad[1])
    return math.acos(max(-1.0, min(1.0, math.cos(roll) * math.cos(pitch))))


@dataclass(frozen=True)
class FallDetectorParams(Params):
    # A standing or walking HRP-2 tilts a few degrees; a robot past 30 deg cannot be caught by the ankles
    # (its capture point is far outside any support polygon), so that is a fall.
    max_tilt_deg: float = field(default=30.0, metadata={"unit": "deg", "min": 5.0, "max": 90.0})
    # Feet carrying less than this share of the weight for unloaded_time_s: lying down, or lifted.
    min_load_ratio: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 1.0})
    unloaded_time_s: float = field(default=0.3, metadata={"unit": "s", "min": 0.0, "max": 10.0})


class FallDetector:
    """`update(roll_rad, pitch_rad, foot_fz_n, dt_s)` each tick (the loop calls `check(est, dt_s)`); `reason` is
    None until a fall is detected, then the first reason ("tilt ..." or "feet unloaded ..."), latched for the life
    of the detector (the loop builds a new one when it resets)."""

    def __init__(self, weight_n: float, params: FallDetectorParams | None = None) -> None:
        self.params = params or FallDetectorParams()
        self.weight_n = float(weight_n)
        self.reason: str | None = None
        self._unloaded_s = 0.0

    @property
    def fallen(self) -> bool:
        return self.reason is not None

    def check(self, est: Estimate, dt_s: float) -> str | None:
        """`update` from the loop's estimate of this tick: the attitude and the feet's F/T sensors."""
        roll, pitch, _ = est.base_rpy_rad.tolist()
        return self.update(roll, pitch, foot_load_n(est.wrenches_ext), dt_s)

    def update(self, roll_rad: float, pitch_rad: float, foot_fz_n: float, dt_s: float) -> str | None:
        """Feed one tick of estimated attitude and the summed vertical force on the feet [N]; returns the
        reason once fallen."""
        if self.reason is not None:
            return self.reason
        p = self.params
        # angle between BODY's z axis and the vertical for roll-pitch-yaw attitudes
        tilt = math.degrees(tilt_rad((roll_rad, pitch_rad)))
        if tilt > p.max_tilt_deg:
            self.reason = f"tilt {tilt:.0f} deg > {p.max_tilt_deg:g} deg (KalmanFilter attitude)"
            return self.reason
        if foot_fz_n < p.min_load_ratio * self.weight_n:
            self._unloaded_s += dt_s
            if self._unloaded_s >= p.unloaded_time_s:
                self.reason = (f"feet unloaded: {foot_fz_n:.0f} N < {p.min_load_ratio:g} x weight for "
                               f"{self._unloaded_s:.2f} s")
        else:
            self._unloaded_s = 0.0
        return self.reason


def foot_load_n(wrenches_ext_sensor) -> float:
    """Summed vertical force [N] the feet's F/T sensors read (sensor frame z, after offset removal)."""
    return float(wrenches_ext_sensor[_FEET[0]][2] + wrenches_ext_sensor[_FEET[1]][2])
