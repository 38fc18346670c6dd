"""SoftErrorLimiter: position, velocity and tracking-error limits on the joint command."""

import numpy as np

from controller.core.types import Reference
from controller.layers.soft_error_limiter import LimitedJoints, SoftErrorLimiter, SoftErrorLimiterParams, limit_command
from tests.controller.fakes import make_ctx

N = 30
LO, HI = -np.ones(N), np.ones(N)


def test_limit_command_clamps_position_then_step_then_error():
    q_prev = np.zeros(N)
    q = limit_command(np.full(N, 5.0), q_prev, np.zeros(N), LO, HI, max_step=0.01, max_error=1.0)
    assert np.allclose(q, 0.01)
    q = limit_command(np.full(N, 0.5), np.full(N, 0.5), np.zeros(N), LO, HI, max_step=1.0, max_error=0.2)
    assert np.allclose(q, 0.2)


def test_command_within_limits_passes_through_unchanged():
    el = SoftErrorLimiter(LO, HI, np.zeros(N))
    ref = Reference.from_arrays(np.full(N, 0.001))
    out = el.tick(make_ctx(q=np.zeros(N)), ref)
    assert out is ref
    assert el.status().limited == LimitedJoints(position=(), velocity=(), error=())


def test_out_of_range_command_is_clamped_and_reported_by_joint_name():
    el = SoftErrorLimiter(LO, HI, np.full(N, 0.99), SoftErrorLimiterParams(error_limit_rad=3.0))
    q = np.full(N, 0.99)
    q[3] = 1.5
    out = el.tick(make_ctx(q=np.full(N, 0.99)), Reference.from_arrays(q))
    assert out.q_rad[3] == 1.0
    assert "RLEG_JOINT3" in el.status().limited.position


def test_velocity_is_limited_per_tick():
    p = SoftErrorLimiterParams(velocity_limit_rad_s=2.0, error_limit_rad=3.0)
    el = SoftErrorLimiter(LO, HI, np.zeros(N), p)
    out = el.tick(make_ctx(q=np.zeros(N), dt=0.005), Reference.from_arrays(np.full(N, 0.5)))
    assert np.allclose(out.q_rad, 2.0 * 0.005)
    assert len(el.status().limited.velocity) == N


def test_tracking_error_is_limited_around_the_encoder():
    p = SoftErrorLimiterParams(velocity_limit_rad_s=20.0, error_limit_rad=0.1)
    el = SoftErrorLimiter(LO, HI, np.zeros(N), p)
    q_meas = np.zeros(N)
    out = el.tick(make_ctx(q=q_meas, dt=0.1), Reference.from_arrays(np.full(N, 0.5)))
    assert np.allclose(out.q_rad, 0.1)
    assert "LARM_JOINT6" in el.status().limited.error


def test_disabled_limiter_is_identity():
    el = SoftErrorLimiter(LO, HI, np.zeros(N))
    el.enabled = False
    ref = Reference.from_arrays(np.full(N, 9.0))
    assert el.tick(make_ctx(q=np.zeros(N)), ref) is ref


def test_while_the_auto_balancer_takes_an_emergency_step_the_legs_have_their_own_velocity_limit():
    p = SoftErrorLimiterParams(velocity_limit_rad_s=3.5, emergency_step_velocity_limit_rad_s=4.5, error_limit_rad=3.0)
    dt = 0.005
    for stepping, legs_rad_s in ((False, 3.5), (True, 4.5), (False, 3.5)):
        el = SoftErrorLimiter(LO, HI, np.zeros(N), p)
        ctx = make_ctx(q=np.zeros(N), dt=dt)
        ctx.ports.emergency_step = stepping  # the AutoBalancer's port, set earlier in the same tick
        out = el.tick(ctx, Reference.from_arrays(np.full(N, 0.5)))
        assert np.allclose(out.q_rad[:12], legs_rad_s * dt)  # RLEG, LLEG
        assert np.allclose(out.q_rad[12:], 3.5 * dt)  # the torso, head and arms keep the everyday limit
        assert len(el.status().limited.velocity) == N


def test_new_parameters_move_the_position_margin_at_once():
    hi = float(HI[0])
    el = SoftErrorLimiter(LO, HI, np.full(N, hi), SoftErrorLimiterParams(error_limit_rad=3.0))
    ref = Reference.from_arrays(np.full(N, hi))
    assert el.tick(make_ctx(q=np.full(N, hi)), ref) is ref  # at the limit, no margin: unchanged
    el.set_params(SoftErrorLimiterParams(error_limit_rad=3.0, position_margin_rad=0.01))
    out = el.tick(make_ctx(q=np.full(N, hi)), ref)
    assert out.q_rad[0] == hi - 0.01
