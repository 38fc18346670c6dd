"""RemoveForceOffset layer: F/T sensor offsets and the weight of the parts below each sensor removed."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.errors import InvalidCommand
from controller.kinematics import RobotKinematics
from controller.layer import Layer, Params
from controller.rotations import cross3
from controller.types import Reference, TickContext
from robot.names import FORCE_SENSOR_NAMES

G = 9.80665  # [m/s^2]


@dataclass(frozen=True)
class RemoveForceOffsetParams(Params):
    gravity_m_s2: float = field(default=G, metadata={"unit": "m/s^2", "min": 0.0, "max": 20.0})
    calibration_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.05, "max": 60.0})


def gravity_wrench_in_sensor(mass_kg: float, com_world: np.ndarray, sensor_pos_world: np.ndarray,
                             R_world_sensor: np.ndarray, g: float = G) -> np.ndarray:
    """Wrench [N, N m] of the weight of a part, about the sensor origin, in the sensor frame."""
    f_world = np.array([0.0, 0.0, -mass_kg * g])
    tau_world = cross3(com_world - sensor_pos_world, f_world)
    return np.concatenate((R_world_sensor.T @ f_world, R_world_sensor.T @ tau_world))


class RemoveForceOffset(Layer):
    """Publishes the external wrench on each end part (ground reaction at a foot, load at a hand).

    A sensor reads the wrench the distal part exerts on the limb: the external wrench plus the weight
    of the part below it. This layer subtracts that weight (mass and COM from the model, orientation
    from the encoders and the KalmanFilter attitude) and a calibrated offset.
    """

    name = "rmfo"
    description = "RemoveForceOffset: F/T offsets and the mass below each sensor removed"

    def __init__(self, kinematics: RobotKinematics, params: RemoveForceOffsetParams | None = None) -> None:
        super().__init__()
        self.kin = kinematics
        self.params = params or RemoveForceOffsetParams()
        self.offsets = np.zeros((len(FORCE_SENSOR_NAMES), 6))
        self._calibrating: dict[str, list] = {}

    def set_params(self, params: RemoveForceOffsetParams) -> None:
        self.params = params

    def calibrate(self, sensors: list[str] | None = None) -> None:
        """Average each named sensor's residual over calibration_time_s and store it as its offset
        (hrpsys removeForceSensorOffset). Only meaningful while that part carries no external load."""
        names = list(FORCE_SENSOR_NAMES) if sensors is None else sensors
        bad = [s for s in names if s not in FORCE_SENSOR_NAMES]
        if bad:
            raise InvalidCommand(f"unknown force sensor(s) {bad}; valid: {list(FORCE_SENSOR_NAMES)}")
        for s in names:
            self._calibrating[s] = [0, np.zeros(6), None]

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        est = ctx.estimate
        kin = self.kin
        kin.update_rpy(np.zeros(3), est.base_rpy_rad, ctx.sensors.q_rad)
        raw = ctx.sensors.wrenches
        ext = np.empty_like(raw)
        ext_w = np.empty_like(raw)
        for i, s in enumerate(FORCE_SENSOR_NAMES):
            p, R = kin.frame_pose(s)
            est.sensor_pos_from_base[i] = p
            est.sensor_R_world[i] = R
            if self.enabled:
                m, c = kin.mass_below(s)
                w = raw[i] - gravity_wrench_in_sensor(m, c, p, R, self.params.gravity_m_s2)
                cal = self._calibrating.get(s)
                if cal is not None:
                    cal[0] += 1
                    cal[1] += w
                    if cal[0] * ctx.dt_s >= self.params.calibration_time_s:
                        self.offsets[i] = cal[1] / cal[0]
                        del self._calibrating[s]
                w = w - self.offsets[i]
            else:
                w = raw[i]
            ext[i] = w
            ext_w[i, :3] = R @ w[:3]
            ext_w[i, 3:] = R @ w[3:]
        est.wrenches_ext = ext
        est.wrenches_ext_world = ext_w
        est.com_from_base = kin.com_world()
        return ref

    def status(self) -> dict:
        return {"enabled": self.enabled, "calibrating": sorted(self._calibrating),
                "offsets": self.offsets.tolist()}
