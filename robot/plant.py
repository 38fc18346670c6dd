"""The MuJoCo plant: HRP-2 No.10 as hardware (read sensors, write servo targets, step physics)."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from robot.names import BASE_LINK, FORCE_SENSOR_NAMES, JOINT_NAMES, MJCF_SCENE, NUM_JOINTS
from robot.sensors import GroundTruth, Sensors, frozen_array

#: Scene name -> MJCF file. Other packages' scenes (table, can, wall...) are added here.
SCENES: dict[str, Path] = {
    "default": MJCF_SCENE,
}

#: MuJoCo's force/torque sensors give the wrench the parent exerts on the sensor's body (the distal side);
#: the hardware convention (robot.sensors.Sensors) is the wrench the distal side exerts on the proximal
#: side, so the plant flips the sign (checked numerically: a standing foot then reads fz > 0).
MUJOCO_TO_HARDWARE_WRENCH_SIGN = -1.0


def available_scenes() -> tuple[str, ...]:
    """The scene names MujocoPlant accepts."""
    return tuple(SCENES)


def scene_path(scene: str | Path) -> Path:
    """The MJCF file of a scene name or path; unknown names raise ValueError listing the valid ones."""
    if isinstance(scene, Path):
        return scene
    if scene in SCENES:
        return SCENES[scene]
    if scene.endswith(".xml") and Path(scene).is_file():
        return Path(scene)
    valid = ", ".join(available_scenes())
    raise ValueError(f"unknown scene {scene!r}; valid scenes: {valid} (or a path to an MJCF file)")


class MujocoPlant:
    """HRP-2 No.10 in MuJoCo: 30 position servos, 4 F/T sensors, a BODY gyro and accelerometer."""

    def __init__(self, scene: str | Path = "default", dt_physics: float = 0.001, keyframe: str = "home"):
        if not (np.isfinite(dt_physics) and dt_physics > 0):
            raise ValueError(f"dt_physics must be a positive number of seconds, got {dt_physics!r}")
        self._path = scene_path(scene)
        self._model = mujoco.MjModel.from_xml_path(str(self._path))
        self._model.opt.timestep = dt_physics
        self._data = mujoco.MjData(self._model)
        self._qpos_adr = np.array([self._model.joint(n).qposadr[0] for n in JOINT_NAMES])
        self._dof_adr = np.array([self._model.joint(n).dofadr[0] for n in JOINT_NAMES])
        self._actuator_ids = np.array([self._model.actuator(n).id for n in JOINT_NAMES])
        self._wrench_adr = [
            (self._sensor_slice(f"{name}_force"), self._sensor_slice(f"{name}_torque"))
            for name in FORCE_SENSOR_NAMES
        ]
        self._gyro = self._sensor_slice("imu_gyro")
        self._accel = self._sensor_slice("imu_accel")
        self._base_id = self._model.body(BASE_LINK).id
        self._base_qpos = self._model.jnt_qposadr[self._model.body_jntadr[self._base_id]]
        self._base_dof = self._model.jnt_dofadr[self._model.body_jntadr[self._base_id]]
        self._push_end_s: dict[int, float] = {}
        self.reset(keyframe)

    def __repr__(self) -> str:
        return f"MujocoPlant(scene={self._path.name!r}, dt_physics={self.dt_physics}, t={self.time_s:.3f} s)"

    def _sensor_slice(self, name: str) -> slice:
        sensor = self._model.sensor(name)
        return slice(sensor.adr[0], sensor.adr[0] + sensor.dim[0])

    # ------------------------------------------------------------------ properties

    @property
    def model(self) -> mujoco.MjModel:
        return self._model

    @property
    def data(self) -> mujoco.MjData:
        return self._data

    @property
    def dt_physics(self) -> float:
        return float(self._model.opt.timestep)

    @property
    def time_s(self) -> float:
        return float(self._data.time)

    # ------------------------------------------------------------------ hardware interface

    def reset(self, keyframe: str = "home") -> None:
        """Reset to a keyframe of the scene (joint targets included); unknown names raise ValueError."""
        names = [self._model.key(i).name for i in range(self._model.nkey)]
        if keyframe not in names:
            raise ValueError(f"unknown keyframe {keyframe!r}; valid keyframes: {', '.join(names)}")
        mujoco.mj_resetDataKeyframe(self._model, self._data, names.index(keyframe))
        self._push_end_s.clear()
        self._sensor_mean = None
        mujoco.mj_forward(self._model, self._data)

    def read(self) -> Sensors:
        """The robot's own sensors: encoders, F/T wrenches (sensor frames), BODY gyro and accelerometer."""
        d = self._data
        data = self._sensor_mean if self._sensor_mean is not None else d.sensordata
        wrenches = np.array([
            MUJOCO_TO_HARDWARE_WRENCH_SIGN * np.concatenate([data[f], data[t]])
            for f, t in self._wrench_adr
        ])
        return Sensors(
            time_s=self.time_s,
            q_rad=frozen_array(d.qpos[self._qpos_adr]),
            dq_rad_s=frozen_array(d.qvel[self._dof_adr]),
            wrenches=frozen_array(wrenches),
            gyro_rad_s=frozen_array(data[self._gyro]),
            accel_m_s2=frozen_array(data[self._accel]),
        )

    def ground_truth(self) -> GroundTruth:
        """The simulator's view of the robot (for tests and rendering, never for the controller)."""
        d = self._data
        quat = d.qpos[self._base_qpos + 3:self._base_qpos + 7]
        R_world_base = d.xmat[self._base_id].reshape(3, 3)
        return GroundTruth(
            time_s=self.time_s,
            base_pos_world=frozen_array(d.qpos[self._base_qpos:self._base_qpos + 3]),
            base_quat_wxyz=frozen_array(quat),
            base_linvel_world=frozen_array(d.qvel[self._base_dof:self._base_dof + 3]),
            base_angvel_world=frozen_array(R_world_base @ d.qvel[self._base_dof + 3:self._base_dof + 6]),
            com_world=frozen_array(d.subtree_com[self._base_id]),
            body_pos_world=frozen_array(d.xpos),
            body_quat_wxyz=frozen_array(d.xquat),
        )

    def write(self, q_ref_rad) -> None:
        """Set the 30 position-servo targets [rad], JOINT_NAMES order."""
        q = np.asarray(q_ref_rad, dtype=float)
        if q.shape != (NUM_JOINTS,):
            raise ValueError(f"q_ref_rad must have shape ({NUM_JOINTS},) in JOINT_NAMES order, got {q.shape}")
        if not np.all(np.isfinite(q)):
            bad = [JOINT_NAMES[i] for i in np.flatnonzero(~np.isfinite(q))]
            raise ValueError(f"q_ref_rad must be finite; not finite at {', '.join(bad)}")
        self._data.ctrl[self._actuator_ids] = q

    def step(self, n: int = 1) -> None:
        """Advance `n` physics steps, ending pushes whose duration has elapsed."""
        if n < 0:
            raise ValueError(f"n must be >= 0, got {n}")
        if n == 0:
            return
        # The IMU and F/T sensors report the mean over the steps since the last read, as a real
        # sensor's anti-aliasing filter does: a single sample, taken in phase with the servo command
        # updates, would see the 1 kHz servo vibration as a biased acceleration.
        total = np.zeros_like(self._data.sensordata)
        for _ in range(n):
            mujoco.mj_step(self._model, self._data)
            total += self._data.sensordata
            self._end_pushes()
        self._sensor_mean = total / n

    def push(self, body: str, force_world_n, duration_s: float) -> None:
        """Apply a world-frame force [N] at `body`'s COM for `duration_s` of simulated time."""
        names = [self._model.body(i).name for i in range(1, self._model.nbody)]
        if body not in names:
            raise ValueError(f"unknown body {body!r}; valid bodies: {', '.join(names)}")
        force = np.asarray(force_world_n, dtype=float)
        if force.shape != (3,) or not np.all(np.isfinite(force)):
            raise ValueError(f"force_world_n must be 3 finite numbers [N], got {force_world_n!r}")
        if not duration_s > 0:
            raise ValueError(f"duration_s must be > 0, got {duration_s!r}")
        body_id = self._model.body(body).id
        self._data.xfrc_applied[body_id, :3] = force
        self._data.xfrc_applied[body_id, 3:] = 0.0
        self._push_end_s[body_id] = self.time_s + duration_s - 0.5 * self.dt_physics

    def _end_pushes(self) -> None:
        for body_id, end_s in list(self._push_end_s.items()):
            if self.time_s >= end_s:
                self._data.xfrc_applied[body_id] = 0.0
                del self._push_end_s[body_id]

    def warnings(self) -> dict[str, int]:
        """Nonzero MuJoCo warning counters since the last reset: name -> count."""
        out = {}
        for i, w in enumerate(self._data.warning):
            if w.number:
                out[mujoco.mjtWarning(i).name] = int(w.number)
        return out
