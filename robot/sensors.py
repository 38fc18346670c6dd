"""What the hardware interface hands the controller each tick (hrpsys RobotHardware ports), and the
simulator's ground truth kept apart from it (for tests and the GUI only, never for the controller)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def frozen_array(values, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """A float64 copy of `values` that cannot be written to (`values` itself if it already is one: a read-only
    float64 array owning its data)."""
    if type(values) is np.ndarray and not values.flags.writeable and values.base is None \
            and values.dtype == np.float64 and (shape is None or values.shape == shape):
        return values
    a = np.array(values, dtype=float, copy=True)
    if shape is not None and a.shape != shape:
        raise ValueError(f"expected shape {shape}, got {a.shape}")
    a.setflags(write=False)  # (half the cost of a.flags.writeable = False)
    return a


def frozen_in_place(a: np.ndarray) -> np.ndarray:
    """`a`, a float64 array just built that nobody else holds, made read-only without the copy frozen_array makes."""
    a.setflags(write=False)
    return a


@dataclass(frozen=True, slots=True)
class Sensors:
    """One reading of the robot's own sensors.

    Wrench convention (as a real F/T sensor between a limb and its end part): the wrench that the
    distal side (foot + ground, hand + load) exerts on the proximal side, at the sensor origin, in the
    sensor frame, `[fx, fy, fz, tx, ty, tz]` [N, N m]. Standing still, each foot sensor reads a positive
    fz: its share of the weight minus the weight of the foot below it.
    """

    time_s: float
    q_rad: np.ndarray  # (30,) joint encoders, JOINT_NAMES order
    dq_rad_s: np.ndarray  # (30,) joint velocities (encoder differentiation)
    wrenches: np.ndarray  # (4, 6) FORCE_SENSOR_NAMES order, sensor frame
    gyro_rad_s: np.ndarray  # (3,) angular velocity of BODY in the BODY frame
    accel_m_s2: np.ndarray  # (3,) specific force of BODY in the BODY frame (+9.81 z when still)


_COS_45_DEG = float(np.cos(np.deg2rad(45.0)))


def is_fallen(truth: GroundTruth) -> bool:
    """The simulation's verdict: BODY lower than 0.35 m, or its z axis more than 45 deg from vertical."""
    w, x, y, z = truth.base_quat_wxyz.tolist()
    up_z = 1.0 - 2.0 * (x * x + y * y)  # z component of BODY's z axis in world
    return bool(truth.base_pos_world[2] < 0.35 or up_z < _COS_45_DEG)


@dataclass(frozen=True, slots=True)
class GroundTruth:
    """The simulator's view. Tests and the GUI may read it; the controller must not."""

    time_s: float
    base_pos_world: np.ndarray  # (3,) BODY origin [m]
    base_quat_wxyz: np.ndarray  # (4,) BODY orientation
    base_linvel_world: np.ndarray  # (3,) [m/s]
    base_angvel_world: np.ndarray  # (3,) [rad/s]
    com_world: np.ndarray  # (3,) whole-robot centre of mass [m]
    body_pos_world: np.ndarray  # (nbody, 3) every MuJoCo body, for rendering
    body_quat_wxyz: np.ndarray  # (nbody, 4)
    # the whole simulation state a renderer needs (the operator's camera view, drawn from the published state)
    qpos: np.ndarray | None = None  # (nq,) every joint of the scene, free objects included
    mocap_pos: np.ndarray | None = None  # (nmocap, 3) fixed objects placed by the simulator [m]
    mocap_quat: np.ndarray | None = None  # (nmocap, 4)
