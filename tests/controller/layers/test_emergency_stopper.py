"""EmergencyStopper, Eq. 15, on a synthetic planned stream: all three cases, then release."""

import numpy as np
import pytest

from controller.core.errors import InvalidState
from controller.core.types import Reference
from controller.layers.emergency_stopper import EmergencyStopper, EmergencyStopperParams, MotionReverter
from tests.controller.fakes import make_ctx

DT = 0.005


def planned(t: float) -> np.ndarray:
    """A synthetic x_seq(t): every dimension ramps at 0.1 per second (joints [rad], wrenches [N]...)."""
    return np.full(63, 0.1 * t)


def ref_at(t: float) -> Reference:
    x = planned(t)
    return Reference.from_arrays(x[:30], x[30:33], x[33:36], x[36:39], x[39:].reshape(4, 6))


def run(es, t0, t1, flag=lambda t: False):
    """Tick from t0 to t1 (inclusive); returns times and packed outputs."""
    ts, out = [], []
    for k in range(int(round((t1 - t0) / DT)) + 1):
        t = t0 + k * DT
        ctx = make_ctx(t=t, dt=DT)
        ctx.last_ports.cp_flag = flag(t)  # the Stabilizer's flag of the tick before
        r = es.tick(ctx, ref_at(t))
        ts.append(t)
        out.append(np.concatenate((r.q_rad, r.base_pos_world, r.base_rpy_rad, r.zmp_base, r.wrenches.ravel())))
    return np.array(ts), np.array(out)


def test_without_a_flag_the_output_is_the_input():
    es = EmergencyStopper(DT)
    ts, out = run(es, 0.0, 2.0)
    assert np.array_equal(out, np.array([planned(t) for t in ts]))


def test_on_the_flag_it_reverts_to_the_plan_t1_earlier_exactly_at_t2_with_zero_velocity_and_holds():
    p = EmergencyStopperParams(t1_s=0.5, t2_s=0.4)
    es = EmergencyStopper(DT, p)
    t_emer = 2.0
    ts, out = run(es, 0.0, 4.0, flag=lambda t: abs(t - t_emer) < 1e-9)
    k_emer = int(round(t_emer / DT))
    k_end = int(round((t_emer + p.t2_s) / DT))
    target = planned(t_emer - p.t1_s)
    # case 1 before the flag
    assert np.allclose(out[:k_emer], [planned(t) for t in ts[:k_emer]])
    # case 3 during the revert: from x_es(t_emer - dt), velocity-continuous (the plan's 0.1/s carries it
    # on briefly, by under 5 mm here), then back to the target
    seg = out[k_emer - 1:k_end + 1, 0]
    assert seg.max() - seg[0] < 0.005
    assert seg[-1] < seg[0]
    # reaches x_seq(t_emer - T1) exactly at t_emer + T2, with zero velocity
    assert np.array_equal(out[k_end], target)
    assert np.max(np.abs(out[k_end] - out[k_end - 1])) / DT < 1e-3
    # case 2 after: holds while the plan goes on
    assert np.all(out[k_end:] == target)
    assert es.status().stopped and es.status().reason == "capture_point"


def test_the_revert_starts_without_a_velocity_jump():
    es = EmergencyStopper(DT, EmergencyStopperParams(t1_s=0.5, t2_s=0.5))
    ts, out = run(es, 0.0, 3.0, flag=lambda t: abs(t - 2.0) < 1e-9)
    v = np.diff(out[:, 0]) / DT
    assert np.max(np.abs(np.diff(v))) < 0.1 * 1.0  # velocity changes by < 0.1 rad/s per tick (plan runs at 0.1)


def test_release_blends_back_to_the_live_plan_without_a_jump():
    p = EmergencyStopperParams(t1_s=0.5, t2_s=0.5, recover_time_s=1.0)
    es = EmergencyStopper(DT, p)
    run(es, 0.0, 3.0, flag=lambda t: abs(t - 2.0) < 1e-9)
    es.release_motion()
    ts, out = run(es, 3.005, 5.0)
    steps = np.abs(np.diff(out[:, 0]))
    assert np.max(steps) < 0.01  # no jump: the gap was 0.15, closed over 1 s
    assert np.allclose(out[-1], planned(ts[-1]), atol=1e-12)  # back on the plan after recover_time_s
    assert not es.status().stopped and not es.status().recovering


def test_the_operator_stop_is_latched_until_release_and_release_when_running_is_an_error():
    es = EmergencyStopper(DT, EmergencyStopperParams(t1_s=0.0, t2_s=0.0))
    run(es, 0.0, 1.0)
    es.stop_motion()
    ts, out = run(es, 1.005, 4.0)
    assert np.max(np.abs(out - out[0])) < 1e-12  # frozen for 3 s (T1 = T2 = 0: hrpsys's plain freeze)
    assert es.status().reason == "operator"
    es.release_motion()
    with pytest.raises(InvalidState, match="not stopped"):
        EmergencyStopper(DT).release_motion()


def test_sample_at_picks_the_latest_sample_not_after_the_time():
    r = MotionReverter(EmergencyStopperParams(t1_s=1.0), DT)
    for k in range(400):
        r.push(k * DT, np.array([k * DT]))
    assert r.sample_at(1.0)[0] == pytest.approx(1.0)
    assert r.sample_at(1.0024)[0] == pytest.approx(1.0)
    assert r.sample_at(-5.0)[0] == r._history[0][1][0]  # older than the buffer: the oldest kept


def test_an_emergency_step_stops_the_motion_like_the_flag_and_says_so():
    es = EmergencyStopper(DT, EmergencyStopperParams(t1_s=0.5, t2_s=0.4))
    for k in range(400):
        t = k * DT
        ctx = make_ctx(t=t, dt=DT)
        ctx.last_ports.emergency_step = k >= 300  # the AutoBalancer's port of the tick before
        es.tick(ctx, ref_at(t))
    assert es.stopped and es.status().reason == "emergency_step"
    assert ctx.ports.motion_stopped  # the operation layer freezes too
    with pytest.raises(InvalidState, match="still up"):  # the step still being taken: refused, not re-latched
        es.release_motion()
    ctx = make_ctx(t=2.0, dt=DT)
    es.tick(ctx, ref_at(2.0))  # the step is over
    es.release_motion()
    assert not es.stopped


@pytest.mark.parametrize("up_s", [0.005, 0.5, 2.0])
def test_a_release_while_the_flag_is_still_up_is_refused_and_succeeds_once_it_drops(up_s):
    es = EmergencyStopper(DT, EmergencyStopperParams(t1_s=0.1, t2_s=0.1))
    run(es, 0.0, 1.0 + up_s - DT, flag=lambda t: t >= 1.0)
    assert es.stopped and es.status().reason == "capture_point"
    with pytest.raises(InvalidState, match="capture-point flag"):
        es.release_motion()
    assert es.stopped
    run(es, 1.0 + up_s, 1.0 + up_s + DT)  # the flag dropped
    es.release_motion()
    run(es, 1.0 + up_s + 2 * DT, 2.0 + up_s)
    assert not es.stopped  # released, and not latched again
