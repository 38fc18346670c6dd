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
_ZERO3 = np.zeros(3)
_ZERO3.flags.writeable = False


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
        self._frame_ids: list[int] | None = None  # sensor frames and the joints below them, FORCE_SENSOR_NAMES order
        self._below_joints: list[int] = []
        self._masses: list[float] = []

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
        kin.update_rpy(_ZERO3, est.base_rpy_rad, ctx.sensors.q_rad)
        raw = ctx.sensors.wrenches
        data = kin.data
        oMf = data.oMf
        H = np.array([oMf[fid].homogeneous for fid in self._sensor_frame_ids()])  # (n, 4, 4) world <- sensor
        est.sensor_pos_from_base[:] = H[:, :3, 3]  # sensor origins, world axes from BODY [m]
        est.sensor_R_world[:] = H[:, :3, :3]
        H_rows = H.tolist()
        Rs = [h[:3] for h in H_rows]  # rows of [R | p] (the 4th column is ignored below)
        if self.enabled:
            g = self.params.gravity_m_s2
            com = data.com
            ext_rows = []
            for i, raw_i in enumerate(raw.tolist()):
                j = self._below_joints[i]
                # weight of the part, about the sensor origin, in the sensor frame (gravity_wrench_in_sensor)
                fz = -self._masses[i] * g
                c0, c1, c2 = com[j].tolist()
                p0, p1, p2 = H_rows[i][0][3], H_rows[i][1][3], H_rows[i][2][3]
                r0, r1, r2 = c0 - p0, c1 - p1, c2 - p2
                t0, t1, t2 = r1 * fz - r2 * 0.0, r2 * 0.0 - r0 * fz, r0 * 0.0 - r1 * 0.0  # cross3(r, (0, 0, fz))
                (a00, a01, a02, _), (a10, a11, a12, _), (a20, a21, a22, _) = Rs[i]
                ext_rows.append((
                    raw_i[0] - (a00 * 0.0 + a10 * 0.0 + a20 * fz),
                    raw_i[1] - (a01 * 0.0 + a11 * 0.0 + a21 * fz),
                    raw_i[2] - (a02 * 0.0 + a12 * 0.0 + a22 * fz),
                    raw_i[3] - (a00 * t0 + a10 * t1 + a20 * t2),
                    raw_i[4] - (a01 * t0 + a11 * t1 + a21 * t2),
                    raw_i[5] - (a02 * t0 + a12 * t1 + a22 * t2),
                ))
            ext = np.array(ext_rows)
            if self._calibrating:
                for i, s in enumerate(FORCE_SENSOR_NAMES):
                    cal = self._calibrating.get(s)
                    if cal is not None:
                        cal[0] += 1
                        cal[1] += ext[i]
                        if cal[0] * ctx.dt_s >= self.params.calibration_time_s:
                            self.offsets[i] = cal[1] / cal[0]
                            del self._calibrating[s]
            ext -= self.offsets
        else:
            ext = np.array(raw, dtype=float)
        ext_w = []
        for R, w in zip(Rs, ext.tolist(), strict=True):  # world-aligned: R f, R tau
            (a00, a01, a02, _), (a10, a11, a12, _), (a20, a21, a22, _) = R
            f0, f1, f2, t0, t1, t2 = w
            ext_w.append((a00 * f0 + a01 * f1 + a02 * f2, a10 * f0 + a11 * f1 + a12 * f2,
                          a20 * f0 + a21 * f1 + a22 * f2, a00 * t0 + a01 * t1 + a02 * t2,
                          a10 * t0 + a11 * t1 + a12 * t2, a20 * t0 + a21 * t1 + a22 * t2))
        est.wrenches_ext = ext
        est.wrenches_ext_world = np.array(ext_w)
        est.com_from_base = kin.com_world()
        return ref

    def _sensor_frame_ids(self) -> list[int]:
        ids = self._frame_ids
        if ids is None:
            kin = self.kin
            ids = self._frame_ids = [kin.frame_ids[s] for s in FORCE_SENSOR_NAMES]
            below = kin._below_joint
            self._below_joints = [below[s] for s in FORCE_SENSOR_NAMES]
            # a subtree's mass does not depend on the configuration: read once (after an update)
            self._masses = [float(kin.data.mass[j]) for j in self._below_joints]
        return ids

    def status(self) -> dict:
        return {"enabled": self.enabled, "calibrating": sorted(self._calibrating),
                "offsets": self.offsets.tolist()}
