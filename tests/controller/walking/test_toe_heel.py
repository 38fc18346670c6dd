"""[MLC] Fig. 4: toe-heel phases (i)-(v), per-foot COP offsets, Eq. 4 ZMP and foot pitch offsets."""

import math
import os
from pathlib import Path

import numpy as np
import pytest

from controller.interpolation.hoff_arbib import hoff_arbib, min_jerk
from controller.walking.footsteps import FootstepParams
from controller.walking.gait_generator import GaitGenerator
from controller.walking.toe_heel import ToeHeelParams, cop_offset_x, foot_pitch_offset, phase_boundaries_s

DT = 0.005
TOE, HEEL = math.radians(15.0), math.radians(10.0)  # [rad]
FIG4 = ToeHeelParams(use_cop_transition=True)  # 0.05 / 0.25 / 0.4 / 0.25 / 0.05 s of a 1.0 s step, 0.137 / -0.10 m
ROOT = Path(__file__).resolve().parents[2]


def fig4_walk(dx=0.2):
    """A 2-step walk (node 0, left, right) with toe-heel contact; returns the generator and its samples."""
    gg = GaitGenerator(dt_s=DT, toe_heel=FIG4,
                       footstep_params=FootstepParams(toe_angle_rad=TOE, heel_angle_rad=HEEL))
    steps = gg.set_footsteps([("rleg", [0, -0.095, 0], [0, 0, 0]), ("lleg", [dx, 0.095, 0], [0, 0, 0]),
                              ("rleg", [dx, -0.095, 0], [0, 0, 0])])
    samples = []
    while gg.walking:
        samples.append(gg.tick())
    return gg, steps, samples


def test_the_phase_boundaries_are_those_of_fig4():
    assert phase_boundaries_s(1.0, FIG4) == pytest.approx([0.0, 0.05, 0.3, 0.7, 0.95, 1.0])
    assert phase_boundaries_s(1.0, FIG4, backward=True) == pytest.approx([0.0, 0.05, 0.3, 0.7, 0.95, 1.0])
    other = ToeHeelParams(0.1, 0.2, 0.3, 0.3, 0.1)
    assert phase_boundaries_s(2.0, other, backward=True) == pytest.approx([0.0, 0.2, 0.8, 1.4, 1.8, 2.0])


def test_the_cop_offset_goes_sole_toe_heel_sole_linearly_in_phases_ii_to_iv():
    bounds = phase_boundaries_s(1.0, FIG4)
    assert cop_offset_x(bounds, 1.0, FIG4) == pytest.approx([0.0, 0.0, 0.137, -0.10, 0.0, 0.0])
    t = np.linspace(0.0, 1.0, 2001)
    cop = cop_offset_x(t, 1.0, FIG4)
    assert np.all(cop[t <= 0.05] == 0.0) and np.all(cop[t >= 0.95] == 0.0)
    for lo, hi, sign in ((0.05, 0.3, 1), (0.3, 0.7, -1), (0.7, 0.95, 1)):
        seg = cop[(t >= lo) & (t <= hi)]
        assert np.all(sign * np.diff(seg) >= 0.0)
        assert np.allclose(np.diff(seg, 2), 0.0, atol=1e-12)  # linear


def test_the_pitch_offset_is_min_jerk_in_each_phase_with_extremes_toe_and_minus_heel():
    bounds = phase_boundaries_s(1.0, FIG4)
    assert foot_pitch_offset(bounds, 1.0, TOE, HEEL, FIG4) == pytest.approx([0.0, 0.0, TOE, -HEEL, 0.0, 0.0])
    t = np.linspace(0.0, 1.0, 2001)
    pitch = foot_pitch_offset(t, 1.0, TOE, HEEL, FIG4)
    assert np.all(pitch[t <= 0.05] == 0.0) and np.all(pitch[t >= 0.95] == 0.0)
    for lo, hi, sign in ((0.05, 0.3, 1), (0.3, 0.7, -1), (0.7, 0.95, 1)):
        assert np.all(sign * np.diff(pitch[(t >= lo) & (t <= hi)]) >= 0.0)
    assert foot_pitch_offset(0.05 + 0.25 * 0.3, 1.0, TOE, HEEL, FIG4) == pytest.approx(TOE * float(min_jerk(0.3)))
    assert (pitch.min(), pitch.max()) == pytest.approx((-HEEL, TOE), abs=1e-5)


def test_min_jerk_is_the_hoff_arbib_path_from_rest_to_rest():
    segment = hoff_arbib(np.array([0.2]), np.array([-0.3]), 0.8)
    for t in (0.0, 0.13, 0.4, 0.8):
        assert segment.sample(t)[0][0] == pytest.approx(0.2 - 0.5 * float(min_jerk(t / 0.8)), abs=1e-12)


def test_backward_steps_run_the_phases_in_reverse_order():
    t = np.linspace(0.0, 1.0, 201)
    forward = foot_pitch_offset(t, 1.0, TOE, HEEL, FIG4)
    backward = foot_pitch_offset(t, 1.0, TOE, HEEL, FIG4, backward=True)
    assert np.allclose(backward, forward[::-1], atol=1e-12)
    assert np.allclose(cop_offset_x(t, 1.0, FIG4, backward=True), cop_offset_x(t, 1.0, FIG4)[::-1], atol=1e-12)
    assert backward[np.argmax(np.abs(backward) > 1e-9)] < 0.0  # heel first
    _, steps, samples = fig4_walk(dx=-0.04)
    pitch_l = np.array([s.pitch_offset_rad[1] for s in samples if s.footstep_index == 1])
    assert pitch_l[np.argmax(np.abs(pitch_l) > 1e-9)] < 0.0
    assert (pitch_l.min(), pitch_l.max()) == pytest.approx((-HEEL, TOE), abs=1e-5)


def test_fig4_walk_follows_the_phases_per_step():
    gg, steps, samples = fig4_walk()
    n = int(round(1.0 / DT))
    for k, f in enumerate(steps[1:], start=1):
        foot = 1 if f.leg == "lleg" else 0
        ticks = [s for s in samples if s.footstep_index == k]
        assert len(ticks) * DT == pytest.approx(1.0, abs=1e-5)
        pitch = np.array([s.pitch_offset_rad[foot] for s in ticks])
        cop = np.array([s.cop_offset_x_m[foot] for s in ticks])
        assert (pitch.min(), pitch.max()) == pytest.approx((-f.heel_angle_rad, f.toe_angle_rad), abs=1e-5)
        t = np.arange(1, n + 1) * DT
        assert cop == pytest.approx(cop_offset_x(t, 1.0, FIG4), abs=1e-12)
        assert np.all(np.array([s.pitch_offset_rad[1 - foot] for s in ticks]) == 0.0)  # support foot flat
        # the toe stays on the ground while toe-off starts in double support (t <= 0.1 s)
        p_key, R_key = ("p_lfoot_world", "R_lfoot_world") if foot else ("p_rfoot_world", "R_rfoot_world")
        for s in ticks[: int(0.1 / DT)]:
            toe = getattr(s, p_key) + getattr(s, R_key) @ [FIG4.toe_offset_x_m, 0.0, 0.0]
            assert toe[2] == pytest.approx(0.0, abs=1e-12)
        # Eq. 4: in single support the ZMP is on the support foot; in double support between the two COPs
        support = [s for s in ticks if s.support != "both"]
        sup_key = "p_rfoot_world" if foot else "p_lfoot_world"
        assert all(np.allclose(s.zmp_world, getattr(s, sup_key)) for s in support)
    zmp = np.array([s.zmp_world for s in samples])
    assert np.max(np.linalg.norm(np.diff(zmp, axis=0), axis=1)) < 0.020
    assert np.max(zmp[:, 0]) <= 0.2 + 1e-12 and np.min(zmp[:, 0]) >= 0.0 - 1e-12
    if os.environ.get("HRP2_SAVE_PLOTS") == "1":
        save_fig4(samples, ROOT / "docs" / "img" / "fig4_toe_heel.png")


def save_fig4(samples, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.array([s.time_s for s in samples])
    fig, ax = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    ax[0].plot(t, [s.cop_offset_x_m[0] for s in samples], label="right foot COP offset x")
    ax[0].plot(t, [s.cop_offset_x_m[1] for s in samples], "--", label="left foot COP offset x")
    ax[0].set_ylabel("[m]")
    ax[0].set_title("(a) COP offsets (sole frame)")
    ax[1].plot(t, [s.zmp_world[0] for s in samples], label="reference ZMP x (Eq. 4)")
    ax[1].plot(t, [s.p_rfoot_world[0] for s in samples], label="right foot x")
    ax[1].plot(t, [s.p_lfoot_world[0] for s in samples], "--", label="left foot x")
    ax[1].set_ylabel("[m]")
    ax[1].set_title("(b) ZMP and foot positions (COG comes from the preview control)")
    ax[2].plot(t, np.degrees([s.pitch_offset_rad[0] for s in samples]), label="right foot")
    ax[2].plot(t, np.degrees([s.pitch_offset_rad[1] for s in samples]), "--", label="left foot")
    ax[2].set_ylabel("[deg]")
    ax[2].set_xlabel("time [s]")
    ax[2].set_title("(c) foot pitch offset (+ toe-off, - heel contact)")
    for a in ax:
        a.grid(True)
        a.legend(fontsize=8)
    fig.suptitle("2-step walk with toe-heel contact: step 1.0 s, phases 0.05/0.25/0.4/0.25/0.05 s")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
