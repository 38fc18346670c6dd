"""The operation IK's parameters: servo speeds, task weights, the joint and COM limits, each with its unit and range."""

from __future__ import annotations

from dataclasses import dataclass, field

from controller.core.layer import Params


@dataclass(frozen=True)
class OperationIKParams(Params):
    """Weights are placo soft-task weights: a task costs weight * |error|^2, hence [1/m^2] or [1/rad^2]."""

    dt_s: float = field(default=0.005, metadata={"unit": "s", "min": 1e-4, "max": 0.1})
    iterations: int = field(default=1, metadata={"unit": "-", "min": 1, "max": 10})
    # below the SoftErrorLimiter's 3.5 rad/s, which must never have to clip this
    joint_velocity_limit_rad_s: float = field(default=2.0, metadata={"unit": "rad/s", "min": 0.01, "max": 3.5})
    # a step toward a position limit covers at most dt / braking_time of the distance left: a joint slows
    # down within joint_velocity_limit * braking_time (0.05 rad by default) of its limit, never hits it
    joint_limit_braking_time_s: float = field(default=0.025, metadata={"unit": "s", "min": 0.001, "max": 1.0})
    # how fast each point's servo target may move toward its target: the largest step asked of the QP
    hand_speed_m_s: float = field(default=0.5, metadata={"unit": "m/s", "min": 0.001, "max": 5.0})
    hand_angular_speed_rad_s: float = field(default=1.5, metadata={"unit": "rad/s", "min": 0.001, "max": 20.0})
    head_angular_speed_rad_s: float = field(default=1.5, metadata={"unit": "rad/s", "min": 0.001, "max": 20.0})
    waist_speed_m_s: float = field(default=0.2, metadata={"unit": "m/s", "min": 0.001, "max": 5.0})
    waist_angular_speed_rad_s: float = field(default=0.5, metadata={"unit": "rad/s", "min": 0.001, "max": 20.0})
    # points >> balance >> posture: a reachable point ends with no steady-state error
    hand_position_weight: float = field(default=100.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    hand_orientation_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    head_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    waist_height_weight: float = field(default=100.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    waist_orientation_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    # without a waist target, BODY height and orientation are held at the reference's with these
    hold_height_weight: float = field(default=10.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    hold_orientation_weight: float = field(default=10.0, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e6})
    foot_position_weight: float = field(default=1e5, metadata={"unit": "1/m^2", "min": 1.0, "max": 1e8})
    foot_orientation_weight: float = field(default=1e4, metadata={"unit": "1/rad^2", "min": 1.0, "max": 1e8})
    # balance autonomy ([OP] Eq. 4): COM x-y held where it was when the points became active (moved to
    # the nearest point inside the margin when the support changes), and kept inside the support polygon
    # with a margin by placo's CoM polygon constraint: hard while the COM is inside the margin, soft with
    # this slack weight while it is outside (e.g. after a change of support), so the QP stays feasible
    com_weight: float = field(default=1.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    # ... and toward a COM target the caller gives (e.g. the gait's COG while stepping): followed, not preferred
    com_track_weight: float = field(default=100.0, metadata={"unit": "1/m^2", "min": 0.0, "max": 1e6})
    com_margin_m: float = field(default=0.035, metadata={"unit": "m", "min": 0.0, "max": 0.1})
    com_polygon_weight: float = field(default=1e3, metadata={"unit": "1/m^2", "min": 1.0, "max": 1e8})
    # upper-body mode: the COM may move at most this far (x and y) from where it was at activation, in the
    # BODY frame, so the AutoBalancer's BODY correction for what the arms and torso did stays this small
    com_guard_m: float = field(default=0.04, metadata={"unit": "m", "min": 0.005, "max": 0.2})
    # ... and approaches it as a capture point would: the guard holds c + dc/dt * T (placo's DCM mode, omega =
    # 1/T), so the COM's speed toward an edge is at most (distance left) / T and it comes to rest at the edge
    # smoothly. A plain position bound stopped it within a tick: the torso reversed at ~20 deg/s, the COM
    # estimate moved 9 mm in 50 ms and the capture-point flag stopped the motion (rhand forward, then up)
    com_guard_braking_time_s: float = field(default=0.25, metadata={"unit": "s", "min": 0.01, "max": 5.0})
    # the torso (the redundancy left once points, feet, BODY and COM are set) pulled to the reference
    posture_weight: float = field(default=1e-3, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e3})
    # ... in the upper-body mode, where no COM task holds the torso back: the arms reach first, the torso
    # helps when they cannot. Measured: 1e-3 folds the chest 52 deg to move the left hand sideways; 3e-3
    # keeps rhand 0.20 m forward exact (chest 14 deg) and the left hand at 4 deg; 1.0 keeps the chest still
    # but the right hand reaches only 0.19 m forward
    upper_body_posture_weight: float = field(default=3e-3, metadata={"unit": "1/rad^2", "min": 0.0, "max": 1e3})
    # damping of every joint step (placo's QP regularisation): no chattering at singularities (straight arm)
    damping_weight: float = field(default=1e-2, metadata={"unit": "1/rad^2", "min": 1e-9, "max": 1.0})
    # below this fraction of the requested step a point is reported limited
    limited_scale: float = field(default=0.9, metadata={"unit": "-", "min": 0.0, "max": 1.0})
    # a requested step shorter than this is "nothing asked" (scale 1): residuals of competing soft tasks
    scale_deadband_m: float = field(default=2e-4, metadata={"unit": "m", "min": 0.0, "max": 1e-2})
    # rotation counts as (angle x this length) beside translation in the scale ratio
    scale_length_m: float = field(default=0.1, metadata={"unit": "m/rad", "min": 0.001, "max": 10.0})
