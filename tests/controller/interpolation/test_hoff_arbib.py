"""Hoff-Arbib interpolator: closed-form quintics (paper Eq. 1-2, hrpsys interpolator) and the track."""

import numpy as np
import pytest

from controller.interpolation.hoff_arbib import (
    HoffArbibTrack,
    Segment,
    eq1_jerk,
    hoff_arbib,
    quintic_coefficients,
    quintic_jerk,
    quintic_state,
    quintic_step,
    stopping_goal,
    via_velocities,
)

DT = 0.005


def play(track, seconds, dt=DT):
    """Step `track` for `seconds`; returns the (x, v, a) samples as three (ticks, n) arrays."""
    xs, vs, accs = [], [], []
    for _ in range(round(seconds / dt)):
        x, v, a = track.step(dt)
        xs.append(x.copy())
        vs.append(v.copy())
        accs.append(a.copy())
    return np.array(xs), np.array(vs), np.array(accs)


def test_quintic_starts_at_the_current_state_and_reaches_the_goal_at_rest():
    x, v, a = np.array([0.1, -0.2]), np.array([0.3, 0.0]), np.array([-1.0, 2.0])
    goal, T = np.array([1.0, -1.0]), 1.7
    c = quintic_coefficients(x, v, a, goal, T)
    for got, want in zip(quintic_state(c, 0.0), (x, v, a), strict=True):
        assert np.allclose(got, want, atol=1e-12)
    xT, vT, aT = quintic_state(c, T)
    assert np.allclose(xT, goal, atol=1e-12)
    assert np.allclose(vT, 0.0, atol=1e-12)
    assert np.allclose(aT, 0.0, atol=1e-12)


def test_quintic_reaches_a_moving_goal_state():
    c = quintic_coefficients(0.0, 1.0, 0.0, 2.0, 1.5, goal_v=-0.5, goal_a=0.25)
    xT, vT, aT = quintic_state(c, 1.5)
    assert np.allclose([xT, vT, aT], [2.0, -0.5, 0.25], atol=1e-12)


def test_quintic_satisfies_eq1_along_the_way():
    x0, v0, a0 = np.array([0.0, 1.0, -0.5]), np.array([0.5, -2.0, 0.0]), np.array([3.0, 0.0, -1.0])
    goal, T = np.array([1.0, -0.3, 0.7]), 2.0
    c = quintic_coefficients(x0, v0, a0, goal, T)
    for t in np.linspace(0.0, T - 0.05, 40):
        x, v, a = quintic_state(c, t)
        jerk = quintic_jerk(c, t)
        expected = eq1_jerk(x, v, a, goal, T - t)
        assert np.allclose(jerk, expected, rtol=1e-6, atol=1e-6 * np.max(np.abs(expected)))


def test_eq2_hoff_arbib_goes_from_rest_to_rest():
    seg = hoff_arbib([0.0, 2.0], [1.0, -2.0], 3.0)
    x, v, a = seg.sample(0.0)
    assert np.allclose(x, [0.0, 2.0]) and np.allclose(v, 0.0) and np.allclose(a, 0.0)
    x, v, _ = seg.sample(1.5)
    assert np.allclose(x, [0.5, 0.0])  # symmetric: halfway at half time
    assert np.allclose(v, np.array([1.0, -4.0]) * 1.875 / 3.0)  # peak speed 15/8 of the mean
    x, v, a = seg.sample(3.0)
    assert np.array_equal(x, [1.0, -2.0]) and np.array_equal(v, [0.0, 0.0]) and np.array_equal(a, [0.0, 0.0])


def test_segment_rejects_non_positive_duration():
    with pytest.raises(ValueError, match="duration_s"):
        Segment.plan(0.0, 0.0, 0.0, 1.0, 0.0)


def test_track_lands_exactly_on_the_goal_at_the_end_time():
    track = HoffArbibTrack(np.array([0.0, 0.3, -1.0]))
    goal = np.array([0.123456789, -0.987654321, 1.0 / 3.0])
    track.go(goal, 1.0)
    xs, vs, accs = play(track, 1.0)
    assert np.array_equal(xs[-1], goal)
    assert np.array_equal(vs[-1], np.zeros(3)) and np.array_equal(accs[-1], np.zeros(3))
    assert not track.is_moving
    assert not np.array_equal(xs[-2], goal)  # it was still moving one tick before


def test_track_holds_its_state_when_idle():
    track = HoffArbibTrack(np.array([0.5]))
    xs, vs, _ = play(track, 0.1)
    assert np.all(xs == 0.5) and np.all(vs == 0.0)


def test_override_mid_motion_stays_velocity_and_acceleration_continuous():
    track = HoffArbibTrack(np.zeros(2))
    track.go(np.array([1.0, -1.0]), 2.0)
    xs1, vs1, as1 = play(track, 1.0)
    track.go(np.array([-0.5, 0.5]), 1.0)  # reverse while fast
    xs2, vs2, as2 = play(track, 1.0)
    xs, vs, accs = (np.concatenate(p) for p in ((xs1, xs2), (vs1, vs2), (as1, as2)))
    # jerk bounded by Eq. 1 at the switch (|a| <= 9|a|/T + 36|v|/T^2 + 60|dx|/T^3, here < 200 per s^3)
    max_jerk = 200.0
    assert np.max(np.abs(np.diff(accs, axis=0))) < max_jerk * DT
    assert np.max(np.abs(np.diff(vs, axis=0))) < np.max(np.abs(accs)) * DT * 1.01 + 1e-12
    assert np.max(np.abs(np.diff(xs, axis=0))) < np.max(np.abs(vs)) * DT * 1.01 + 1e-12
    # the step across the switch looks like every other step
    k = len(xs1)
    assert np.allclose(vs[k] - vs[k - 1], as1[-1] * DT, atol=max_jerk * DT**2)
    assert np.array_equal(xs[-1], [-0.5, 0.5])


def test_via_velocity_is_the_mean_of_same_sign_neighbours_else_zero():
    v = via_velocities([0.0, 0.0], [[1.0, 1.0], [3.0, 0.0], [4.0, 1.0]], [1.0, 1.0, 1.0])
    assert np.allclose(v[0], [1.5, 0.0])  # (1 + 2)/2 ; +1 then -1 -> 0
    assert np.allclose(v[1], [1.5, 0.0])  # (2 + 1)/2 ; -1 then +1 -> 0
    assert np.allclose(v[2], [0.0, 0.0])  # the last goal is at rest


def test_sequence_passes_through_via_points_at_their_times():
    track = HoffArbibTrack(np.zeros(2))
    goals = np.array([[1.0, 1.0], [3.0, 0.0], [4.0, 1.0]])
    track.go_sequence(goals, [1.0, 1.0, 1.0])
    xs, vs, accs = play(track, 3.0)
    for i in range(3):
        k = round((i + 1) / DT) - 1
        assert np.allclose(xs[k], goals[i], atol=1e-12)
        assert np.allclose(accs[k], 0.0, atol=1e-9)
    assert np.allclose(vs[199], [1.5, 0.0], atol=1e-9)
    assert np.array_equal(xs[-1], goals[-1]) and np.array_equal(vs[-1], [0.0, 0.0])
    assert np.max(np.abs(np.diff(vs, axis=0))) < np.max(np.abs(accs)) * DT * 1.01


def test_step_that_crosses_a_segment_boundary_carries_the_leftover_time():
    track = HoffArbibTrack(np.zeros(1))
    track.go_sequence([[1.0], [2.0]], [0.0125, 1.0])
    track.step(DT)
    track.step(DT)
    x, _, _ = track.step(DT)  # 0.015 s: 2.5 ms into the second segment
    expected = track.segments[0].sample(0.0025)[0]
    assert np.allclose(x, expected, atol=1e-12)


def test_brake_comes_to_rest_without_reversing():
    track = HoffArbibTrack(np.zeros(1))
    track.go(np.array([1.0]), 2.0)
    play(track, 1.0)
    x0, v0, a0 = track.x.copy(), track.v.copy(), track.a.copy()
    track.brake(0.5)
    xs, vs, _ = play(track, 0.5)
    assert np.all(vs[:-1] * v0 > 0.0)
    assert np.array_equal(xs[-1], stopping_goal(x0, v0, a0, 0.5))
    assert np.array_equal(vs[-1], [0.0]) and not track.is_moving


def test_stop_freezes_where_it_is():
    track = HoffArbibTrack(np.zeros(3))
    track.go(np.ones(3), 1.0)
    x_mid, _, _ = (a.copy() for a in track.step(0.5))
    track.stop()
    x, v, a = track.step(DT)
    assert np.array_equal(x, x_mid) and np.array_equal(v, np.zeros(3)) and np.array_equal(a, np.zeros(3))


def test_take_keeps_the_selected_dimensions_on_the_same_schedule():
    track = HoffArbibTrack(np.zeros(3))
    track.go(np.array([1.0, 2.0, 3.0]), 1.0)
    play(track, 0.4)
    sub = track.take(np.array([False, True, True]))
    for _ in range(10):
        x_full, _, _ = track.step(DT)
        x_sub, _, _ = sub.step(DT)
        assert np.array_equal(x_full[1:], x_sub)
    assert sub.remaining_s == pytest.approx(track.remaining_s)


def test_quintic_step_replans_toward_the_goal_and_lands_on_it():
    x, v, a = np.zeros(2), np.zeros(2), np.zeros(2)
    goal, remaining = np.array([1.0, -1.0]), 0.5
    for _ in range(100):
        x, v, a = quintic_step(x, v, a, goal, remaining, DT)
        remaining -= DT
    assert np.array_equal(x, goal) and np.array_equal(v, [0.0, 0.0])
