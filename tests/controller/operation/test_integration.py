"""One tick of an operated point: speed limit, acceleration ramp from the last tick's twist, integration (unit)."""

import numpy as np
import pytest

from controller.layers.operation import OperationParams
from controller.operation.integration import PointLimits, integrate_point
from controller.operation.points import Twist
from controller.operation.targets import HandPose, WaistPose

DT = 0.005


def test_a_twist_within_its_limits_moves_the_target_by_twist_times_dt():
    h = HandPose.of((0.3, -0.2, 0.8), np.eye(3))
    twist = Twist.of((0.1, 0.0, 0.0))
    step = integrate_point(h, twist, twist, (0.3, 1.0), (1.0, 1.0), DT)
    assert step.rate is twist and not step.velocity_limited
    assert np.allclose(step.target.p_feet_m, (0.3 + 0.1 * DT, -0.2, 0.8))


def test_a_too_fast_twist_is_scaled_down_and_flagged():
    w = WaistPose(0.6, (0.0, 0.0, 0.0))
    step = integrate_point(w, Twist.of((0.0, 0.0, -0.4)), Twist.of((0.0, 0.0, -0.1)), (0.1, 0.5), (1.0, 1.0), DT)
    assert step.velocity_limited
    assert step.rate.linear_m_s[2] == pytest.approx(-0.1)
    assert step.target.height_m == pytest.approx(0.6 - 0.1 * DT)


def test_from_rest_the_twist_ramps_up_by_the_acceleration_step():
    h = HandPose.of((0.3, -0.2, 0.8), np.eye(3))
    step = integrate_point(h, Twist.of((0.2, 0.0, 0.0)), None, (0.3, 1.0), (0.5 * DT, 4.0 * DT), DT)
    assert step.rate.linear_m_s[0] == pytest.approx(0.5 * DT)  # 0.5 m/s^2 for one tick
    assert not step.velocity_limited
    assert step.target.p_feet_m[0] == pytest.approx(0.3 + 0.5 * DT * DT)


def test_the_limit_tables_follow_the_parameters_and_the_tick():
    limits, p = PointLimits(), OperationParams()
    assert limits.speed(p, "rhand") == (p.hand_speed_m_s, p.hand_angular_speed_rad_s)
    assert limits.speed(p, "head") == (1.0, p.head_angular_speed_rad_s)
    assert limits.accel_steps(p, "waist", DT) == (p.waist_accel_m_s2 * DT, p.waist_angular_accel_rad_s2 * DT)
    faster = OperationParams(hand_speed_m_s=0.5)
    assert limits.speed(faster, "lhand")[0] == 0.5
    assert limits.accel_steps(faster, "lhand", 2 * DT)[0] == faster.hand_accel_m_s2 * 2 * DT


def test_a_point_come_to_rest_has_no_rate_and_the_fused_step_is_limit_then_ramp_bit_for_bit():
    from controller.operation.limits import limit_twist, ramp_twist

    h = HandPose.of((0.3, -0.2, 0.8), np.eye(3))
    assert integrate_point(h, Twist.of(), Twist.of((1e-4, 0.0, 0.0)), (0.3, 1.0), (0.01, 0.01), DT).rate is None
    rng = np.random.default_rng(0)
    for _ in range(200):
        twist = Twist.of(rng.normal(0, 0.3, 3), rng.normal(0, 1.0, 3))
        previous = None if rng.random() < 0.2 else Twist.of(rng.normal(0, 0.3, 3), rng.normal(0, 1.0, 3))
        speed, accel = (0.3, 1.0), tuple(rng.uniform(0.001, 0.5, 2))
        limited = limit_twist(twist, *speed)
        ramped = ramp_twist(previous or Twist.of(), limited.twist, *accel)
        step = integrate_point(h, twist, previous, speed, accel, DT)
        assert np.array_equal(step.rate.linear_m_s, ramped.linear_m_s)
        assert np.array_equal(step.rate.angular_rad_s, ramped.angular_rad_s)
        assert step.velocity_limited == (limited.scale < 1.0)
        assert np.array_equal(step.target.p_feet_m, h.integrated(ramped, DT).p_feet_m)
