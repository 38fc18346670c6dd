"""KalmanFilter layer: BODY attitude (roll, pitch, yaw) from the gyro and the accelerometer ([MLC] III)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.layer import Layer, Params
from controller.rotations import euler_rate_matrix_inv
from controller.types import Reference, TickContext

G = 9.80665  # [m/s^2]


@dataclass(frozen=True)
class KalmanFilterParams(Params):
    q_angle: float = field(default=1e-6, metadata={"unit": "rad^2 per tick", "min": 0.0, "max": 1.0})
    q_bias: float = field(default=1e-9, metadata={"unit": "(rad/s)^2 per tick", "min": 0.0, "max": 1.0})
    r_angle: float = field(default=1e-2, metadata={"unit": "rad^2", "min": 1e-9, "max": 10.0})
    # the accelerometer is trusted less when |a| differs from g by this much or more
    accel_trust_band: float = field(default=0.5 * G, metadata={"unit": "m/s^2", "min": 1e-3, "max": 100.0})


class AttitudeKalmanFilter:
    """Two independent 2-state filters (angle, gyro bias) for roll and pitch; yaw integrates the gyro.

    Prediction integrates the bias-corrected body rate through the Euler-rate map; the measurement
    is the tilt of the specific force seen by the accelerometer. Pure maths, no layer logic.
    """

    def __init__(self, params: KalmanFilterParams, rpy0=(0.0, 0.0, 0.0)) -> None:
        self.params = params
        self.rpy = np.array(rpy0, dtype=float)
        self.bias = np.zeros(2)  # roll, pitch gyro bias [rad/s]
        self.P = np.tile(np.eye(2) * 1e-2, (2, 1, 1))  # per axis (angle, bias)

    @staticmethod
    def tilt_from_accel(accel_m_s2: np.ndarray) -> np.ndarray:
        """Roll and pitch of the body from the specific force it feels when not accelerating."""
        ax, ay, az = accel_m_s2
        return np.array([np.arctan2(ay, az), np.arctan2(-ax, np.hypot(ay, az))])

    def update(self, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray, dt_s: float) -> np.ndarray:
        p = self.params
        omega = np.array(gyro_rad_s, dtype=float)
        omega[:2] -= self.bias
        rate = euler_rate_matrix_inv(self.rpy) @ omega
        self.rpy = self.rpy + rate * dt_s
        # covariance prediction, x = [angle, bias], angle' = angle + (w - bias) dt
        F = np.array([[1.0, -dt_s], [0.0, 1.0]])
        Q = np.diag([p.q_angle, p.q_bias])
        self.P = F @ self.P @ F.T + Q
        # measurement: accelerometer tilt, trusted less under acceleration
        z = self.tilt_from_accel(accel_m_s2)
        excess = abs(np.linalg.norm(accel_m_s2) - G) / p.accel_trust_band
        r = p.r_angle * (1.0 + 100.0 * excess * excess)
        for i in range(2):
            Pi = self.P[i]
            s = Pi[0, 0] + r
            k = Pi[:, 0] / s  # gain for (angle, bias)
            innov = np.arctan2(np.sin(z[i] - self.rpy[i]), np.cos(z[i] - self.rpy[i]))
            self.rpy[i] += k[0] * innov
            self.bias[i] += k[1] * innov
            self.P[i] = Pi - np.outer(k, Pi[0, :])
        self.rpy[2] = np.arctan2(np.sin(self.rpy[2]), np.cos(self.rpy[2]))
        return self.rpy.copy()


class KalmanFilter(Layer):
    """Estimates the BODY attitude every tick into `ctx.estimate`; the reference passes through."""

    name = "kf"
    description = "KalmanFilter: BODY attitude from gyro + accelerometer"

    def __init__(self, params: KalmanFilterParams | None = None, rpy0=(0.0, 0.0, 0.0)) -> None:
        super().__init__()
        self.params = params or KalmanFilterParams()
        self.filter = AttitudeKalmanFilter(self.params, rpy0)

    def set_params(self, params: KalmanFilterParams) -> None:
        self.params = params
        self.filter.params = params

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        s = ctx.sensors
        ctx.estimate.base_rpy_rad = self.filter.update(s.gyro_rad_s, s.accel_m_s2, ctx.dt_s)
        ctx.estimate.base_angvel_rad_s = np.array(s.gyro_rad_s, dtype=float)
        return ref

    def reset(self, ctx: TickContext, ref: Reference) -> None:
        tilt = AttitudeKalmanFilter.tilt_from_accel(ctx.sensors.accel_m_s2)
        self.filter = AttitudeKalmanFilter(self.params, (tilt[0], tilt[1], 0.0))

    def status(self) -> dict:
        return {"enabled": self.enabled, "rpy_deg": np.rad2deg(self.filter.rpy).round(3).tolist(),
                "gyro_bias_deg_s": np.rad2deg(self.filter.bias).round(4).tolist()}
