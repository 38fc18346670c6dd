"""Builds the real-time controller for a plant: the layers in chain order, the loop, the estimators."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from controller.balance.fall_detector import FallDetector
from controller.balance.state_estimation import ActualStateEstimator
from controller.core.chain import Chain
from controller.core.constants import GRAVITY_M_S2
from controller.core.layer import Params
from controller.core.loop import ControlLoop, Plant, Snapshot
from controller.core.types import Reference
from controller.kinematics.model import RobotKinematics
from controller.kinematics.operation_ik import OperationIK
from controller.kinematics.rotations import rpy_to_matrix
from controller.layers.auto_balancer import AutoBalancer
from controller.layers.collision_detector import CollisionDetector
from controller.layers.emergency_stopper import EmergencyStopper
from controller.layers.hard_emergency_stopper import HardEmergencyStopper
from controller.layers.impedance_controller import ImpedanceController
from controller.layers.kalman_filter import AttitudeKalmanFilter, KalmanFilter
from controller.layers.operation import OperationLayer
from controller.layers.remove_force_offset import RemoveForceOffset
from controller.layers.sequence_player import SequencePlayer
from controller.layers.soft_error_limiter import SoftErrorLimiter
from controller.layers.stabilizer import Stabilizer
from robot.sensors import Sensors


def layer_classes() -> dict[str, type]:
    """Layer name -> class of every layer this system builds (chain order)."""
    classes = (KalmanFilter, RemoveForceOffset, SequencePlayer, OperationLayer, EmergencyStopper, ImpedanceController,
               AutoBalancer, Stabilizer, CollisionDetector, HardEmergencyStopper, SoftErrorLimiter)
    return {cls.name: cls for cls in classes}


def layer_params_classes() -> dict[str, type]:
    """Layer name -> the Params class of its parameters, for the layers that have some (the hands'
    impedance parameters are per limb, "ic:<limb>", and not listed here)."""
    import inspect
    import typing

    out = {}
    for name, cls in layer_classes().items():
        if not hasattr(cls, "set_params") or len(inspect.signature(cls.set_params).parameters) != 2:
            continue  # no parameters, or several sets of them (one per limb)
        hint = typing.get_type_hints(cls.set_params).get("params")
        if isinstance(hint, type) and issubclass(hint, Params):
            out[name] = hint
    return out


def initial_reference(kin: RobotKinematics, q_rad: np.ndarray) -> Reference:
    """The reference a freshly started controller assumes: the encoder posture, BODY level at x = y = 0
    and at the height that puts the lower sole on the ground (z = 0)."""
    kin.update_rpy(np.zeros(3), np.zeros(3), q_rad)
    sole_z = min(kin.frame_pose("rfsensor")[0][2], kin.frame_pose("lfsensor")[0][2])
    base = np.array([0.0, 0.0, -sole_z])
    kin.update_rpy(base, np.zeros(3), q_rad)
    com = kin.com_world()
    zmp_base = np.array([com[0], com[1], 0.0]) - base
    return Reference.from_arrays(q_rad, base_pos_world=base, zmp_base=zmp_base)


class ControllerSystem:
    """The controller side of the robot: kinematic model, chain factory, state estimator, loop."""

    def __init__(self, plant: Plant, dt_control_s: float = 0.005,
                 on_snapshot: Callable[[Snapshot], None] | None = None, start_auto_balancer: bool = True,
                 start_stabilizer: bool = True) -> None:
        self.start_auto_balancer = start_auto_balancer
        self.start_stabilizer = start_stabilizer and start_auto_balancer
        self.kin = RobotKinematics()
        # separate kinematics objects: each user updates its own pinocchio data
        self._kin_est = RobotKinematics()
        self._kin_seq = RobotKinematics()
        self._operation_ik = OperationIK(upper_body=True)  # placo's model built once (~0.1 s), reset per chain
        # the one estimator of the actual COG and ZMP, new with every chain: the Stabilizer runs it, the
        # loop only when no layer did (a chain without the Stabilizer)
        self.estimator = ActualStateEstimator(self._kin_est)
        weight_n = self.kin.total_mass * GRAVITY_M_S2
        self.loop = ControlLoop(plant, self.build_chain, dt_control_s=dt_control_s,
                                state_estimator=lambda sensors, est, ref: self.estimator(sensors, est, ref),
                                on_snapshot=on_snapshot, fall_detector_factory=lambda: FallDetector(weight_n))

    def build_chain(self, sensors: Sensors, dt_s: float) -> Chain:
        q0 = np.array(sensors.q_rad, dtype=float)
        ref0 = initial_reference(self.kin, q0)
        tilt = AttitudeKalmanFilter.tilt_from_accel(sensors.accel_m_s2)
        self.estimator = ActualStateEstimator(self._kin_est)
        layers = [
            KalmanFilter(rpy0=(tilt[0], tilt[1], 0.0)),
            RemoveForceOffset(RobotKinematics()),
            SequencePlayer(ref0, dt_s, ik_solver=self._solve_limb_ik),
            OperationLayer(dt_s, ik=self._operation_ik),
            EmergencyStopper(dt_s),
            ImpedanceController(),
            AutoBalancer(ref0, dt_s, active=self.start_auto_balancer),
            Stabilizer(dt_s, active=self.start_stabilizer, estimator=self.estimator),
            CollisionDetector(q0),
            HardEmergencyStopper(q0),
            SoftErrorLimiter(self.kin.q_lower, self.kin.q_upper, q0),
        ]
        return Chain({layer.name: layer for layer in layers})

    def _solve_limb_ik(self, group, q_rad, base_pos_world, base_rpy_rad, target_pos, target_rpy_rad, frame):
        """SequencePlayer's setTargetPose solver: targets as position + roll-pitch-yaw."""
        return self._kin_seq.limb_ik(group, q_rad, base_pos_world, base_rpy_rad, target_pos,
                                     rpy_to_matrix(target_rpy_rad), frame)

    @property
    def chain(self) -> Chain:
        return self.loop.chain
