"""KalmanFilter layer: BODY attitude (roll, pitch, yaw) from the gyro and the accelerometer ([MLC] III), or the
kinematics of the soles lying flat on the ground when the Stabilizer has it."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from controller.core.constants import GRAVITY_M_S2
from controller.core.layer import Layer, Params, Status, described
from controller.core.types import Reference, TickContext, read_only
from controller.kinematics.rotations import rpy_to_rows


@dataclass(frozen=True)
class KalmanFilterParams(Params):
    q_angle: float = field(default=1e-6, metadata={"unit": "rad^2 per tick", "min": 0.0, "max": 1.0})
    q_bias: float = field(default=1e-9, metadata={"unit": "(rad/s)^2 per tick", "min": 0.0, "max": 1.0})
    r_angle: float = field(default=1e-2, metadata={"unit": "rad^2", "min": 1e-9, "max": 10.0})
    # the accelerometer is trusted less when |a| differs from g by this much or more
    accel_trust_band: float = field(default=0.5 * GRAVITY_M_S2, metadata={"unit": "m/s^2", "min": 1e-3, "max": 100.0})
    use_planned_acceleration: bool = field(default=True, metadata={"unit": "-"})
    # ... and less when BODY turns (roll, pitch rate) at this rate or more: the robot rocking after a push
    # accelerates BODY in ways no plan knows, and the accelerometer reads that as tilt (a 20 N s forward push:
    # the attitude first read backward, then 1.4 deg too far forward and 0.1 s late, and the COG estimate with
    # it, 20 mm off). 0.05 did as well on the push but, a hand pulled down, the attitude caught up with the
    # accelerometer in one jump when the turning ended (a 60 mm capture-point spike raised the flag). 0 = off
    gyro_trust_band_rad_s: float = field(default=0.1, metadata={"unit": "rad/s", "min": 0.0, "max": 10.0})
    # the tilt measurement from the kinematics of the soles lying flat on the ground (the Stabilizer's
    # Ports.body_tilt_kin_rad) instead of the accelerometer's whenever there is one: at a foot landing the
    # accelerometer reads the impact as tilt (1.1 deg of pitch, the estimated COG 15-20 mm off and the
    # capture-point error 80 mm on a 3 m walk); the soles do not. r_sole_tilt is its variance
    use_sole_tilt: bool = field(default=True, metadata={"unit": "-"})
    r_sole_tilt: float = field(default=1e-4, metadata={"unit": "rad^2", "min": 1e-9, "max": 10.0})


def _floats3(v) -> list[float]:
    """A 3-vector (array or sequence) as Python floats."""
    return v.tolist() if isinstance(v, np.ndarray) else [float(x) for x in v]


class AttitudeKalmanFilter:
    """Two independent 2-state filters (angle, gyro bias) for roll and pitch; yaw integrates the gyro.

    Prediction integrates the bias-corrected body rate through the Euler-rate map; the measurement
    is the tilt of the specific force seen by the accelerometer. Pure maths, no layer logic.
    """

    def __init__(self, params: KalmanFilterParams, rpy0=(0.0, 0.0, 0.0)) -> None:
        self.params = params
        self.rpy = np.array(rpy0, dtype=float)
        self.bias = np.zeros(2)  # roll, pitch gyro bias [rad/s]
        # per axis covariance of (angle, bias): [p00, p01, p11]
        self._P = [[1e-2, 0.0, 1e-2], [1e-2, 0.0, 1e-2]]

    @property
    def P(self) -> np.ndarray:
        return np.array([[[p00, p01], [p01, p11]] for p00, p01, p11 in self._P])

    @staticmethod
    def tilt_from_accel(accel_m_s2: np.ndarray) -> np.ndarray:
        """Roll and pitch of the body from the specific force it feels when not accelerating."""
        ax, ay, az = (float(v) for v in accel_m_s2)
        return np.array([math.atan2(ay, az), math.atan2(-ax, math.hypot(ay, az))])

    def update(self, gyro_rad_s: np.ndarray, accel_m_s2: np.ndarray | None, dt_s: float,
               tilt_rad: tuple[float, float] | None = None) -> np.ndarray:
        """One predict (gyro) + correct step; scalar maths, it runs every tick. The correction measures the
        tilt with `tilt_rad` (roll, pitch [rad], variance r_sole_tilt) when given, else with the
        accelerometer."""
        p = self.params
        wx, wy, wz = _floats3(gyro_rad_s)
        bias = self.bias.tolist()
        wx -= bias[0]
        wy -= bias[1]
        r, pi, y = self.rpy.tolist()
        # Euler-angle rates of R = Rz Ry Rx from the body rate
        cr, sr, cp, tp = math.cos(r), math.sin(r), math.cos(pi), math.tan(pi)
        r += (wx + sr * tp * wy + cr * tp * wz) * dt_s
        pi += (cr * wy - sr * wz) * dt_s
        y += (sr * wy + cr * wz) / cp * dt_s
        if tilt_rad is not None:
            z = (float(tilt_rad[0]), float(tilt_rad[1]))
            r_meas = p.r_sole_tilt
        else:
            ax, ay, az = _floats3(accel_m_s2)
            z = (math.atan2(ay, az), math.atan2(-ax, math.hypot(ay, az)))
            excess = abs(math.sqrt(ax * ax + ay * ay + az * az) - GRAVITY_M_S2) / p.accel_trust_band
            r_meas = p.r_angle * (1.0 + 100.0 * excess * excess)
            if p.gyro_trust_band_rad_s > 0.0:
                turning = (wx * wx + wy * wy) / (p.gyro_trust_band_rad_s * p.gyro_trust_band_rad_s)
                r_meas *= 1.0 + 100.0 * turning
        angles = [r, pi]
        for i in range(2):
            p00, p01, p11 = self._P[i]
            # predict: angle' = angle + (w - bias) dt  ->  F = [[1, -dt], [0, 1]]
            p00 = p00 - dt_s * (2.0 * p01 - dt_s * p11) + p.q_angle
            p01 = p01 - dt_s * p11
            p11 = p11 + p.q_bias
            # correct with the accelerometer tilt
            s = p00 + r_meas
            k0, k1 = p00 / s, p01 / s
            innov = z[i] - angles[i]
            innov = math.atan2(math.sin(innov), math.cos(innov))
            angles[i] += k0 * innov
            bias[i] += k1 * innov
            self._P[i] = [p00 - k0 * p00, p01 - k0 * p01, p11 - k1 * p01]
        self.bias[:] = bias
        y = math.atan2(math.sin(y), math.cos(y))
        self.rpy = np.array((angles[0], angles[1], y))
        return self.rpy.copy()


@dataclass(frozen=True, slots=True)
class KalmanFilterStatus(Status):
    rpy_rad: tuple[float, float, float] = field(metadata=described("estimated BODY roll, pitch, yaw", "rad"))
    gyro_bias_rad_s: tuple[float, float, float] = field(metadata=described("estimated gyro bias", "rad/s"))


class KalmanFilter(Layer):
    """Estimates the BODY attitude every tick into `ctx.estimate`; the reference passes through."""

    name = "kf"
    description = "KalmanFilter: BODY attitude from gyro + accelerometer (or the flat soles' kinematics)"

    def __init__(self, params: KalmanFilterParams | None = None, rpy0=(0.0, 0.0, 0.0)) -> None:
        super().__init__()
        self.params = params or KalmanFilterParams()
        self.filter = AttitudeKalmanFilter(self.params, rpy0)

    def set_params(self, params: KalmanFilterParams) -> None:
        self.params = params
        self.filter.params = params

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        s = ctx.sensors
        tilt = ctx.last_ports.body_tilt_kin_rad if self.params.use_sole_tilt else None
        if tilt is not None:  # the soles measure the tilt (the accelerometer is not read)
            ctx.estimate.base_rpy_rad = read_only(self.filter.update(s.gyro_rad_s, None, ctx.dt_s, tilt_rad=tilt))
            ctx.estimate.base_angvel_rad_s = np.array(s.gyro_rad_s, dtype=float)
            return ref
        accel = s.accel_m_s2
        cog_acc = ctx.last_ports.cog_acc_world  # the AutoBalancer's plan of the tick before
        if self.params.use_planned_acceleration and cog_acc is not None:
            # the accelerometer feels tilt AND the body's acceleration: remove the planned one (the COG's,
            # the body moves with it) so the walking sway is not read as roll
            (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rpy_to_rows(*self.filter.rpy.tolist())
            a0, a1, a2 = _floats3(accel)
            c0, c1, c2 = _floats3(cog_acc)
            accel = (a0 - (r00 * c0 + r10 * c1 + r20 * c2), a1 - (r01 * c0 + r11 * c1 + r21 * c2),
                     a2 - (r02 * c0 + r12 * c1 + r22 * c2))  # accel - R^T cog_acc
        ctx.estimate.base_rpy_rad = read_only(self.filter.update(s.gyro_rad_s, accel, ctx.dt_s))  # a copy
        ctx.estimate.base_angvel_rad_s = np.array(s.gyro_rad_s, dtype=float)
        return ref

    def status(self) -> KalmanFilterStatus:
        return KalmanFilterStatus(enabled=self.enabled, rpy_rad=tuple(self.filter.rpy.tolist()),
                                  gyro_bias_rad_s=tuple(self.filter.bias.tolist()))
