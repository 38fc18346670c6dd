"""Preview control: cart-table ZMP tracking with hrpsys testGaitGenerator thresholds."""

import os
from pathlib import Path

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.walking.preview_control import PreviewController, PreviewControlParams, PreviewQueue

DT = 0.005  # [s]
ZMP_TRACKING_TOL = 0.050  # [m] |cart ZMP - refzmp| every tick
COG_REST_TOL = 0.0015  # [m] COG vs refzmp at start and end
REFZMP_JUMP = 0.020  # [m] per tick
ZMP_JUMP = 0.020  # [m] per tick
COG_JUMP = 0.010  # [m] per tick


def knots_to_refzmp(knots_t_s, knots_xy_m, duration_s: float, n_preview: int) -> np.ndarray:
    """Piecewise-linear refzmp sampled at every tick, plus n_preview ticks of look-ahead, (n + N + 1, 2)."""
    n = round(duration_s / DT)
    t = np.arange(n + n_preview + 1) * DT
    knots_xy_m = np.asarray(knots_xy_m, dtype=float)
    return np.stack([np.interp(t, knots_t_s, knots_xy_m[:, i]) for i in range(2)], axis=1)


def step_refzmp(n_preview: int, edge_s: float) -> np.ndarray:
    """x 0 -> 0.1 m at 2 s, y 0 -> -0.05 m at 3 s, held 4 s more; each edge is a ramp of edge_s."""
    e = max(edge_s, 1e-9)
    knots_t = [0.0, 2.0, 2.0 + e, 3.0, 3.0 + e, 100.0]
    knots_xy = [[0, 0], [0, 0], [0.1, 0], [0.1, 0], [0.1, -0.05], [0.1, -0.05]]
    return knots_to_refzmp(knots_t, knots_xy, 7.0, n_preview)


def walking_refzmp(n_preview: int) -> np.ndarray:
    """Staircase: ZMP alternates y = -+0.095 every 1.0 s (0.2 s linear transitions), x +0.2 m per step."""
    knots_t, knots_xy = [0.0, 1.0], [[0.0, 0.0], [0.0, 0.0]]
    n_steps = 6
    for k in range(n_steps):
        y = -0.095 if k % 2 == 0 else 0.095
        start = 1.0 + k * 1.0
        knots_t += [start + 0.2, start + 1.0]
        knots_xy += [[0.2 * k, y], [0.2 * k, y]]
    end = 1.0 + n_steps * 1.0
    knots_t += [end + 0.2, 100.0]
    knots_xy += [[0.2 * (n_steps - 1), 0.0], [0.2 * (n_steps - 1), 0.0]]
    return knots_to_refzmp(knots_t, knots_xy, end + 2.5, n_preview)


def run(pc: PreviewController, ref: np.ndarray):
    """Feed ref[k+1 .. k+N] at tick k; returns COG, cart ZMP and the refzmp they should track, (n, 2) each."""
    n_prev = pc.preview_length
    n = len(ref) - n_prev - 1
    pc.reset(ref[0])
    queue = PreviewQueue(n_prev, ref[0])
    for j in range(n_prev):
        queue.push(ref[1 + j])
    cog, zmp = np.empty((n, 2)), np.empty((n, 2))
    for k in range(n):
        cog[k], _, _, zmp[k] = pc.update(queue.view)
        queue.push(ref[k + 1 + n_prev])
    return cog, zmp, ref[1 : n + 1]


def max_jump(a: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(a, axis=0), axis=1).max())


@pytest.fixture(scope="module")
def controller():
    return PreviewController(PreviewControlParams(dt_s=DT))


def save_step_plot(cog, zmp, ref, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(1, len(ref) + 1) * DT
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
    for i, (ax, name) in enumerate(zip(axes, "xy", strict=True)):
        ax.plot(t, ref[:, i] * 1e3, "k--", label="refzmp")
        ax.plot(t, zmp[:, i] * 1e3, label="cart-table ZMP")
        ax.plot(t, cog[:, i] * 1e3, label="COG")
        ax.set_ylabel(f"{name} [mm]")
        ax.grid(True, alpha=0.3)
    axes[0].set_title(f"Preview control, ZMP step (dt {DT} s, preview 1.6 s, Q 1, R 1e-6)")
    axes[0].legend(loc="lower right")
    axes[1].set_xlabel("time [s]")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def test_preview_length_is_the_preview_time_in_ticks(controller):
    assert controller.preview_length == round(1.6 / DT) == 320
    assert controller.gains.f.shape == (320,)


def test_a_zmp_step_is_tracked_within_the_hrpsys_thresholds(controller):
    ref = step_refzmp(controller.preview_length, edge_s=0.05)
    cog, zmp, ref_now = run(controller, ref)
    assert max_jump(ref_now) < REFZMP_JUMP
    assert np.linalg.norm(zmp - ref_now, axis=1).max() < ZMP_TRACKING_TOL
    assert np.linalg.norm(cog[0] - ref_now[0]) < COG_REST_TOL
    assert np.linalg.norm(cog[-1] - ref_now[-1]) < COG_REST_TOL
    assert max_jump(cog) < COG_JUMP
    assert max_jump(zmp) < ZMP_JUMP
    if os.environ.get("HRP2_SAVE_PLOTS") == "1":
        save_step_plot(cog, zmp, ref_now, Path(__file__).parents[2] / "docs" / "img" / "preview_zmp_step.png")


def test_a_hard_zmp_step_is_still_tracked_within_50_mm(controller):
    cog, zmp, ref_now = run(controller, step_refzmp(controller.preview_length, edge_s=0.0))
    assert np.linalg.norm(zmp - ref_now, axis=1).max() < ZMP_TRACKING_TOL
    assert np.linalg.norm(cog[-1] - ref_now[-1]) < COG_REST_TOL


def test_a_walking_staircase_refzmp_is_tracked_within_50_mm(controller):
    cog, zmp, ref_now = run(controller, walking_refzmp(controller.preview_length))
    assert np.linalg.norm(zmp - ref_now, axis=1).max() < ZMP_TRACKING_TOL
    assert max_jump(cog) < COG_JUMP
    assert max_jump(zmp) < ZMP_JUMP
    assert np.linalg.norm(cog[-1] - ref_now[-1]) < COG_REST_TOL
    # the COG sways less than the ZMP (it stays between the feet)
    assert np.abs(cog[:, 1]).max() < 0.095


def test_the_gains_do_not_depend_on_the_axis(controller):
    ref = step_refzmp(controller.preview_length, edge_s=0.05)
    same = np.stack([ref[:, 0], ref[:, 0]], axis=1)
    cog, zmp, _ = run(controller, same)
    assert np.array_equal(cog[:, 0], cog[:, 1]) and np.array_equal(zmp[:, 0], zmp[:, 1])
    cog_swapped, _, _ = run(controller, ref[:, ::-1].copy())
    cog_plain, _, _ = run(controller, ref)
    assert np.allclose(cog_swapped, cog_plain[:, ::-1], atol=1e-15)


def test_the_controller_stays_at_rest_for_a_constant_ref(controller):
    zmp0 = np.array([0.3, -0.1])
    controller.reset(zmp0)
    queue = PreviewQueue(controller.preview_length, zmp0)
    for _ in range(400):
        pos, vel, acc, zmp = controller.update(queue.view)
        queue.push(zmp0)
    assert np.allclose(pos, zmp0, atol=1e-12) and np.allclose(zmp, zmp0, atol=1e-12)
    assert np.allclose(vel, 0.0, atol=1e-12) and np.allclose(acc, 0.0, atol=1e-12)


def test_the_riccati_solution_satisfies_the_extended_dare(controller):
    g, p = controller.gains, controller.params
    A_e = np.zeros((4, 4))
    A_e[0, 0], A_e[0, 1:], A_e[1:, 1:] = 1.0, g.C @ g.A, g.A
    B_e = np.concatenate(([g.C @ g.B], g.B)).reshape(4, 1)
    P = g.P
    K = (B_e.T @ P @ A_e) / (p.r + (B_e.T @ P @ B_e).item())
    residual = A_e.T @ P @ A_e - P - A_e.T @ P @ B_e @ K + np.diag([p.q, 0, 0, 0])
    assert np.abs(residual).max() < 1e-6 * np.abs(P).max()


def test_preview_gains_fade_out_within_the_preview_horizon(controller):
    f = controller.gains.f
    assert abs(f[-1]) < 0.01 * np.abs(f).max()


def test_the_queue_keeps_the_next_n_refs_oldest_first():
    q = PreviewQueue(3, (0.0, 0.0))
    for i in range(1, 5):
        q.push((i, -i))
    assert np.array_equal(q.view, [[2, -2], [3, -3], [4, -4]])
    with pytest.raises(ValueError):
        q.view[0, 0] = 1.0


def test_update_rejects_a_ref_of_the_wrong_length(controller):
    with pytest.raises(InvalidCommand):
        controller.update(np.zeros((10, 2)))
