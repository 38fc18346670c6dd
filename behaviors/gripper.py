"""The JRL-hand as the behaviours see it: its joint, which way closes, and the fingertip force the controller
can sense from its own signals (the servo's position error and the encoder's rate), within the hand's 14 N
fingertip limit (the gripper actuator's torque is capped at 14 N x the pad depth, see robot/robot_model.py)."""

from __future__ import annotations

from dataclasses import dataclass

from robot.generate import FINGER_PAD_DEPTH_M, GRIP_FORCE_LIMIT_N, SERVO_CLASSES

GRIPPER_KP_N_M_RAD, GRIPPER_KV_N_M_S_RAD, _ = SERVO_CLASSES["gripper_servo"]  # the hand's servo gains
TORQUE_LIMIT_N_M = GRIP_FORCE_LIMIT_N * FINGER_PAD_DEPTH_M
FINGERTIP_LIMIT_N = GRIP_FORCE_LIMIT_N
SETTLED_RAD_S = 0.05  # [rad/s] the jaw is at rest below this rate


def gripper_joint(hand: str) -> str:
    """The gripper joint of "rhand" / "lhand" (the arm's last joint; its upper limit closes the jaw)."""
    return {"rhand": "RARM_JOINT6", "lhand": "LARM_JOINT6"}[hand]


def fingertip_force_n(q_cmd_rad: float, q_meas_rad: float, dq_meas_rad_s: float) -> float:
    """The closing force at the fingertip pad [N] from the servo law tau = kp (q_cmd - q) - kv dq, capped at
    the actuator's limit: what presses on an object between the jaws (0 when opening or free)."""
    tau = GRIPPER_KP_N_M_RAD * (q_cmd_rad - q_meas_rad) - GRIPPER_KV_N_M_S_RAD * dq_meas_rad_s
    return max(0.0, min(tau, TORQUE_LIMIT_N_M)) / FINGER_PAD_DEPTH_M


def squeeze_offset_rad(force_n: float) -> float:
    """How far past the measured jaw angle to command so that the servo presses with `force_n` [N] at rest."""
    return min(force_n, FINGERTIP_LIMIT_N) * FINGER_PAD_DEPTH_M / GRIPPER_KP_N_M_RAD


@dataclass
class JawRate:
    """The jaw's rate from successive encoder readings [rad/s] (the snapshot has no joint velocities)."""

    dt_s: float
    last_rad: float | None = None
    rate_rad_s: float = 0.0

    def update(self, q_rad: float) -> float:
        if self.last_rad is not None:
            self.rate_rad_s = (q_rad - self.last_rad) / self.dt_s
        self.last_rad = q_rad
        return self.rate_rad_s
