"""The one start/stop blend: sigmoid_ratio, Transition (both shapes) and RecoverBlend."""

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.interpolation.blend import SHAPES, RecoverBlend, Transition, sigmoid_ratio

DT = 0.005  # [s] the control period


def weights(t: Transition, dt_s: float = DT) -> list[float]:
    """Every weight `t` gives until done (at most one tick past its duration)."""
    out = []
    for _ in range(int(t.duration_s / dt_s) + 2):
        out.append(t.step(dt_s))
        if t.done:
            return out
    raise AssertionError(f"{t!r} not done one tick past its duration")


def test_sigmoid_ratio_goes_exactly_from_0_to_1_symmetric_about_the_middle():
    assert sigmoid_ratio(0.0) == 0.0 and sigmoid_ratio(1.0) == 1.0
    assert sigmoid_ratio(0.5) == pytest.approx(0.5, abs=1e-15)
    s = np.linspace(0.0, 1.0, 101)
    r = np.array([sigmoid_ratio(v) for v in s])
    assert np.all(np.diff(r) > 0.0)
    np.testing.assert_allclose(r + r[::-1], 1.0, atol=1e-15)
    assert sigmoid_ratio(-0.3) == 0.0 and sigmoid_ratio(1.7) == 1.0  # progress clamped


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize(("w0", "w1"), [(0.0, 1.0), (1.0, 0.0), (0.25, 0.75)])
def test_a_transition_starts_at_w0_moves_monotonically_and_ends_exactly_at_w1_after_its_duration(shape, w0, w1):
    t = Transition(w0, w1, 0.8, shape)
    assert t.weight == w0 and not t.done and t.elapsed_s == 0.0
    w = weights(t)
    assert len(w) == 160  # 0.8 s at 5 ms (measured: exactly; not before, never more than one tick after)
    assert w[-1] == w1 and t.weight == w1 and t.done
    steps = np.diff([w0, *w]) * np.sign(w1 - w0)
    assert np.all(steps >= 0.0) and steps.sum() == pytest.approx(abs(w1 - w0))
    assert t.step(DT) == w1  # stepping past the end stays there


@pytest.mark.parametrize("shape", SHAPES)
def test_a_transition_starts_and_ends_at_rest(shape):
    w = weights(Transition(0.0, 1.0, 1.0, shape))
    steps = np.diff([0.0, *w])
    assert steps[0] < 0.1 * steps.max() and steps[-1] < 0.1 * steps.max()  # smooth ends, not a ramp
    assert w[99] == pytest.approx(0.5, abs=0.01)  # halfway in time, halfway in weight (both are symmetric)


def test_the_min_jerk_shape_is_the_hoff_arbib_quintic():
    t = Transition(0.0, 2.0, 1.0, "min_jerk")
    for k, w in enumerate(weights(t), start=1):
        s = k * DT
        assert w == pytest.approx(2.0 * (10 * s**3 - 15 * s**4 + 6 * s**5), abs=1e-9)


@pytest.mark.parametrize("shape", SHAPES)
def test_a_transition_restarted_mid_blend_from_its_weight_goes_on_without_a_jump(shape):
    up = Transition(0.0, 1.0, 1.0, shape)
    for _ in range(80):
        up.step(DT)
    mid = up.weight
    down = Transition(up.weight, 0.0, 1.0, shape)  # how a layer stops while starting
    assert down.weight == mid
    w = weights(down)
    assert abs(w[0] - mid) < 0.01 and w[-1] == 0.0
    assert np.all(np.diff(w) <= 0.0)


def test_transition_arguments_are_validated_naming_what_would_work():
    with pytest.raises(InvalidCommand, match="valid: sigmoid, min_jerk"):
        Transition(0.0, 1.0, 1.0, "linear")
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InvalidCommand, match="must be > 0"):
            Transition(0.0, 1.0, bad)


def test_recover_blend_leaves_the_held_value_smoothly_and_ends_exactly_on_the_moving_input():
    x0 = np.array([0.0, 1.0])
    blend = RecoverBlend(x0, 0.5)
    assert not blend.done and blend.remaining_s == 0.5
    out, remaining = [], []
    for k in range(100):
        target = np.array([1.0, -1.0]) + 0.1 * k * DT  # the live input keeps moving
        y = blend.step(target, DT)
        out.append(y)
        remaining.append(blend.remaining_s)
        if blend.done:
            break
    assert len(out) == 100 and blend.done and remaining[-1] == 0.0  # 0.5 s at 5 ms
    assert np.all(np.diff(remaining) < 0.0)
    np.testing.assert_allclose(out[0], x0, atol=1e-4)  # min-jerk: the first tick barely leaves x0
    assert np.array_equal(out[-1], target) and out[-1] is not target  # exactly the input, a copy
    # in between: x0 + w (input - x0) with w between 0 and 1
    w = (out[49] - x0) / (np.array([1.0, -1.0]) + 0.1 * 49 * DT - x0)
    assert w[0] == pytest.approx(w[1]) and 0.4 < w[0] < 0.6


def test_a_recover_blend_of_no_duration_gives_the_input_at_once():
    blend = RecoverBlend(np.zeros(3), 0.0)
    assert np.array_equal(blend.step(np.ones(3), DT), np.ones(3)) and blend.done


def test_a_recover_blend_carrying_the_motion_passes_the_inputs_motion_unscaled_and_blends_out_the_gap():
    x0 = np.array([0.0, 1.0])
    blend = RecoverBlend(x0, 0.5, carry_motion=True)
    first = np.array([0.2, 0.9])
    out, targets = [], []
    for k in range(100):
        target = first + 0.1 * k * DT  # moving from the first input on
        targets.append(target)
        out.append(blend.step(target, DT))
    out, targets = np.array(out), np.array(targets)
    np.testing.assert_allclose(out[0], x0, atol=1e-4)  # it starts where it was held
    assert np.array_equal(out[-1], targets[-1])  # and ends exactly on the input
    # in between: input + (1 - w) (x0 - first input): the input's motion since the first step passes whole
    one_minus_w = (out[:-1] - targets[:-1]) / (x0 - first)
    np.testing.assert_allclose(one_minus_w[:, 0], one_minus_w[:, 1], atol=1e-12)
    assert np.all(np.diff(one_minus_w[:, 0]) <= 1e-15) and one_minus_w[49, 0] == pytest.approx(0.5, abs=0.1)


def test_a_recover_blend_carrying_the_motion_is_the_plain_blend_for_a_still_input():
    plain, carry = RecoverBlend(np.zeros(3), 0.3), RecoverBlend(np.zeros(3), 0.3, carry_motion=True)
    for _ in range(70):
        np.testing.assert_allclose(carry.step(np.ones(3), DT), plain.step(np.ones(3), DT), atol=1e-15)
