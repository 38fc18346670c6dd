"""Swing orbits: they start and end exactly on the footholds, peak at the step height, and the trapezoid orbit's
horizontal speed peaks at 4/3 of its mean where the cycloid's reaches twice it."""

import numpy as np
import pytest

from controller.walking.swing_trajectory import ORBIT_TYPES, swing_position

S = np.linspace(0.0, 1.0, 4001)
SRC, DST = np.array([0.0, -0.1, 0.0]), np.array([0.4, 0.1, 0.0])


@pytest.mark.parametrize("orbit", ORBIT_TYPES)
def test_every_orbit_starts_and_ends_on_the_footholds_and_peaks_at_the_step_height(orbit):
    p = swing_position(S, SRC, DST, 0.04, orbit)
    assert p[0] == pytest.approx(SRC, abs=1e-12) and p[-1] == pytest.approx(DST, abs=1e-12)
    assert p[:, 2].max() == pytest.approx(0.04, abs=1e-6)
    assert np.max(np.linalg.norm(np.diff(p, axis=0), axis=1)) < 1e-3  # continuous


def horizontal_speed(orbit):
    p = swing_position(S, SRC, DST, 0.04, orbit)
    return np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1) / np.diff(S) / np.linalg.norm(DST[:2] - SRC[:2])


def test_the_trapezoid_orbits_horizontal_speed_peaks_at_four_thirds_of_its_mean_the_cycloids_at_twice():
    assert horizontal_speed("trapezoid").max() == pytest.approx(4.0 / 3.0, rel=1e-3)
    assert horizontal_speed("cycloid").max() == pytest.approx(2.0, rel=1e-3)
    # the trapezoid ramps its speed up and down smoothly (no step in speed)
    assert np.max(np.abs(np.diff(horizontal_speed("trapezoid")))) < 0.01


def test_the_trapezoid_has_the_cycloids_height_profile():
    assert swing_position(S, SRC, DST, 0.04, "trapezoid")[:, 2] == pytest.approx(
        swing_position(S, SRC, DST, 0.04, "cycloid")[:, 2])


def test_an_unknown_orbit_names_the_valid_ones():
    with pytest.raises(ValueError, match="trapezoid"):
        swing_position(S, SRC, DST, 0.04, "zigzag")
