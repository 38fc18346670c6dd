"""RemoveForceOffset layer: F/T sensor offsets and the weight of the parts below each sensor removed."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand
from controller.core.layer import Layer, Params, SharedStatus, Status, described
from controller.core.types import Reference, TickContext, read_only
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import cross3
from robot.names import FORCE_SENSOR_NAMES

_ZERO3 = np.zeros(3)
read_only(_ZERO3)
_NO_OFFSETS = bytes(8 * 6 * len(FORCE_SENSOR_NAMES))  # the bytes of all-zero offsets (a cheap test)


#: [1/rad] the COM below a sensor is recomputed when a joint further down (the jaw) moves by 1e-4 rad: the jaw's
#: encoder jitters by ~1e-8 rad every tick, and 1e-4 rad moves the hand's COM by 0.33 um (a moment of 3 uN m)
_COM_KEY_PER_RAD = 1e4


@dataclass(frozen=True)
class RemoveForceOffsetParams(Params):
    gravity_m_s2: float = field(default=GRAVITY_M_S2, metadata={"unit": "m/s^2", "min": 0.0, "max": 20.0})
    calibration_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.05, "max": 60.0})


def gravity_wrench_in_sensor(mass_kg: float, com_world: np.ndarray, sensor_pos_world: np.ndarray,
                             R_world_sensor: np.ndarray, g: float = GRAVITY_M_S2) -> np.ndarray:
    """Wrench [N, N m] of the weight of a part, about the sensor origin, in the sensor frame."""
    f_world = np.array([0.0, 0.0, -mass_kg * g])
    tau_world = cross3(com_world - sensor_pos_world, f_world)
    return np.concatenate((R_world_sensor.T @ f_world, R_world_sensor.T @ tau_world))


@dataclass(frozen=True, slots=True)
class RemoveForceOffsetStatus(Status):
    calibrating: tuple[str, ...] = field(metadata=described("sensors whose offset is being measured"))
    offsets: tuple[tuple[float, ...], ...] = field(metadata=described(
        "offset of each sensor (FORCE_SENSOR_NAMES order), fx fy fz [N] tx ty tz [N m]"))


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
        # per sensor: the joint below it, the mass below it, the q indices of the joints further down, sensor <-
        # joint rotation and the sensor's origin in the joint frame; the COMs in the sensor frames and the joint
        # values they are for
        self._below: list[tuple[int, float, list[int], np.ndarray, np.ndarray]] = []
        self._coms: list[tuple[float, float, float]] = []
        self._com_keys: list[list[int] | None] = []
        self._offsets_status = SharedStatus()

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
        kin.update_joints_rpy(_ZERO3, est.base_rpy_rad, ctx.sensors.q_rad)  # only the sensor frames are read
        frame = kin.frame_homogeneous
        H = np.array([frame(fid) for fid in self._sensor_frame_ids()])  # (n, 4, 4) world <- sensor
        est.sensor_pos_from_base = H[:, :3, 3]  # sensor origins, world axes from BODY [m]
        est.sensor_R_world = H[:, :3, :3]
        H_rows = H.tolist()  # per sensor, rows of [R | p] as floats
        if self.enabled:
            ext_rows = self._external_wrenches(H_rows, ctx.sensors.wrenches.tolist())
            if self._calibrating:
                self._calibrate_step(ext_rows, ctx.dt_s)
            if self.offsets.tobytes() != _NO_OFFSETS:  # ext - offsets (none before a calibration: x - 0 is x)
                ext_rows = [[e - o for e, o in zip(row, off, strict=True)]
                            for row, off in zip(ext_rows, self.offsets.tolist(), strict=True)]
        else:
            ext_rows = ctx.sensors.wrenches.tolist()
        ext_w = []
        for h, w in zip(H_rows, ext_rows, strict=True):  # world-aligned: R f, R tau
            (a00, a01, a02, _), (a10, a11, a12, _), (a20, a21, a22, _), _ = h
            f0, f1, f2, t0, t1, t2 = w
            ext_w.append((a00 * f0 + a01 * f1 + a02 * f2, a10 * f0 + a11 * f1 + a12 * f2,
                          a20 * f0 + a21 * f1 + a22 * f2, a00 * t0 + a01 * t1 + a02 * t2,
                          a10 * t0 + a11 * t1 + a12 * t2, a20 * t0 + a21 * t1 + a22 * t2))
        est.wrenches_ext = read_only(np.array(ext_rows))  # published in the snapshot as it is
        est.wrenches_ext_world = np.array(ext_w)
        est.com_from_base = kin.com_world()
        return ref

    def _external_wrenches(self, H_rows: list, raw_rows: list) -> list[tuple[float, ...]]:
        """Each raw wrench minus the weight of the part below its sensor (gravity_wrench_in_sensor on floats:
        f = R^T (0, 0, -m g), tau = R^T ((c - p) x f_world), the products with zero left out), with c - p = R c_s
        from the part's COM in the sensor frame, c_s. pinocchio keeps a subtree's COM (data.com[j], j > 0) in its
        joint's frame (taken as a world COM it was 0.34 m off at the wrists, 0.09 m at the ankles: 2.7 and 1.5 N m
        of moment that was not there); the sensor is fixed in that joint's frame, so c_s only moves with the joints
        further down (the gripper's jaw): recomputed when they move by 1 / _COM_KEY_PER_RAD (their encoders jitter
        every tick)."""
        g = self.params.gravity_m_s2
        q = self.kin.q
        coms, keys = self._coms, self._com_keys
        out = []
        for i, (h, raw_i, (j, mass, moving, s_R_j, j_p_s)) in enumerate(zip(H_rows, raw_rows, self._below,
                                                                             strict=True)):
            if moving:
                key = [int(q.item(k) * _COM_KEY_PER_RAD) for k in moving]
                if key != keys[i]:
                    coms[i] = tuple((s_R_j @ (self.kin.data.com[j] - j_p_s)).tolist())
                    keys[i] = key
            s0, s1, s2 = coms[i]
            (a00, a01, a02, _), (a10, a11, a12, _), (a20, a21, a22, _), _ = h
            fz = -mass * g
            d0, d1 = a00 * s0 + a01 * s1 + a02 * s2, a10 * s0 + a11 * s1 + a12 * s2  # c - p, world, x and y
            t0, t1 = d1 * fz, -(d0 * fz)  # (c - p) x (0, 0, fz), world; its z is 0
            out.append((raw_i[0] - a20 * fz, raw_i[1] - a21 * fz, raw_i[2] - a22 * fz,
                        raw_i[3] - (a00 * t0 + a10 * t1), raw_i[4] - (a01 * t0 + a11 * t1),
                        raw_i[5] - (a02 * t0 + a12 * t1)))
        return out

    def _calibrate_step(self, ext_rows: list, dt_s: float) -> None:
        """Accumulate the offset-free residuals of the sensors being calibrated; store finished offsets."""
        for i, s in enumerate(FORCE_SENSOR_NAMES):
            cal = self._calibrating.get(s)
            if cal is not None:
                cal[0] += 1
                cal[1] += ext_rows[i]
                if cal[0] * dt_s >= self.params.calibration_time_s:
                    self.offsets[i] = cal[1] / cal[0]
                    del self._calibrating[s]

    def _sensor_frame_ids(self) -> list[int]:
        ids = self._frame_ids
        if ids is None:
            kin = self.kin
            ids = self._frame_ids = [kin.frame_ids[s] for s in FORCE_SENSOR_NAMES]
            model, data = kin.model, kin.data
            self._below, self._coms = [], []
            for fid, sensor in zip(ids, FORCE_SENSOR_NAMES, strict=True):
                j = kin.joint_below(sensor)
                mass = float(data.mass[j])  # a subtree's mass does not depend on the configuration: read once
                j_M_s = model.frames[fid].placement  # the sensor in its joint's frame (fixed)
                s_R_j, j_p_s = j_M_s.rotation.T.copy(), j_M_s.translation.copy()
                moving = [int(model.joints[k].idx_q) for k in model.subtrees[j] if k != j]
                self._below.append((j, mass, moving, s_R_j, j_p_s))
                self._coms.append(tuple((s_R_j @ (data.com[j] - j_p_s)).tolist()))  # fixed if nothing moves
            self._com_keys = [None] * len(ids)
        return ids

    def status(self) -> RemoveForceOffsetStatus:
        offsets = self._offsets_status.get(self.offsets.tobytes(), lambda: tuple(map(tuple, self.offsets.tolist())))
        return RemoveForceOffsetStatus(enabled=self.enabled, calibrating=tuple(sorted(self._calibrating)),
                                       offsets=offsets)
