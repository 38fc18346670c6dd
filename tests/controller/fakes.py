"""Small fakes shared by the controller unit tests: a TickContext from chosen sensor values."""

import numpy as np

from controller.core.types import Estimate, TickContext
from robot.sensors import Sensors


def make_sensors(q=None, t=0.0, wrenches=None, gyro=(0.0, 0.0, 0.0), accel=(0.0, 0.0, 9.80665)):
    return Sensors(
        time_s=t,
        q_rad=np.zeros(30) if q is None else np.asarray(q, dtype=float),
        dq_rad_s=np.zeros(30),
        wrenches=np.zeros((4, 6)) if wrenches is None else np.asarray(wrenches, dtype=float),
        gyro_rad_s=np.asarray(gyro, dtype=float),
        accel_m_s2=np.asarray(accel, dtype=float),
    )


def make_ctx(q=None, t=0.0, dt=0.005, tick=0, **kw) -> TickContext:
    return TickContext(tick=tick, time_s=t, dt_s=dt, sensors=make_sensors(q=q, t=t, **kw), estimate=Estimate())
