"""Force-moment distribution QP (Eq. 9-14): non-negative vertex forces that realise the target ZMP."""

import numpy as np
import pytest
from scipy.optimize import nnls

from controller.balance.force_distribution import (
    QP_SOLVERS,
    FootPolygon,
    ForceDistributionQP,
    ForceDistributionWeights,
    alpha_from_zmp,
    distribute_zmp_to_feet,
)
from controller.core.errors import InvalidCommand

MG = 58.0 * 9.80665  # [N]
FRONT, REAR, HALF_WIDTH = 0.13, 0.10, 0.0675  # [m], HRP-2-like sole
RFOOT, LFOOT = np.array([0.0, -0.1]), np.array([0.0, 0.1])  # [m]


def rect_foot(center_xy, cop_offset=(0.0, 0.0)):
    c = np.asarray(center_xy, dtype=float)
    corners = np.array([[FRONT, HALF_WIDTH], [FRONT, -HALF_WIDTH], [-REAR, -HALF_WIDTH], [-REAR, HALF_WIDTH]])
    return FootPolygon(c + corners, c + np.asarray(cop_offset))


def both_feet():
    return [rect_foot(RFOOT), rect_foot(LFOOT)]


def zmp_of(result):
    """ZMP [m] rebuilt from the per-foot outputs only: COP = p_cop + (n_y, -n_x) / fz (Eq. 13-14)."""
    cops = np.array([foot.cop_ref_xy for foot in both_feet()[: len(result.fz_n)]])
    cops = cops + np.column_stack((result.n_xy_nm[:, 1], -result.n_xy_nm[:, 0])) / result.fz_n[:, None]
    return result.fz_n @ cops / result.fz_n.sum()


def inside(point, vertices, tol=1e-9):
    """Point in a convex polygon given in any order (vertices sorted by angle about their mean)."""
    c = vertices.mean(axis=0)
    v = vertices[np.argsort(np.arctan2(*(vertices - c).T[::-1]))]
    e = np.roll(v, -1, axis=0) - v
    rel = point - v
    return bool(np.all(e[:, 0] * rel[:, 1] - e[:, 1] * rel[:, 0] >= -tol))


def projection_by_nnls(point, vertices):
    """Nearest point of conv(vertices) by non-negative least squares on convex weights (independent check)."""
    w = 1e4
    A = np.vstack([vertices.T, w * np.ones(len(vertices))])
    lam, _ = nnls(A, np.append(point, w))
    return vertices.T @ (lam / lam.sum())


TARGETS_INSIDE = {
    "between the feet": (0.02, 0.0),
    "under the right foot": (0.03, -0.1),
    "under the left foot at its heel": (-0.08, 0.12),
    "near the front edge": (0.1299, 0.05),
    "at an outer corner": (FRONT, -0.1 - HALF_WIDTH),
}


@pytest.mark.parametrize("target", list(TARGETS_INSIDE.values()), ids=list(TARGETS_INSIDE))
def test_resulting_zmp_equals_a_target_inside_the_support_polygon(target):
    alpha = alpha_from_zmp(np.array(target), RFOOT, LFOOT)
    r = distribute_zmp_to_feet(np.array(target), MG, both_feet(), alpha)
    assert not r.projected
    assert np.allclose(zmp_of(r), target, atol=1e-6)
    assert np.allclose(r.zmp_world_xy, target, atol=1e-12)


@pytest.mark.parametrize("target", list(TARGETS_INSIDE.values()), ids=list(TARGETS_INSIDE))
def test_vertex_forces_are_non_negative_and_sum_to_the_commanded_force(target):
    r = distribute_zmp_to_feet(np.array(target), MG, both_feet(), 0.5)
    f = np.concatenate(r.vertex_fz_n)
    assert f.min() >= -1e-6
    assert abs(f.sum() - MG) <= 1e-6 * MG
    assert abs(r.fz_n.sum() - MG) <= 1e-6 * MG


@pytest.mark.parametrize("target", [(0.5, 0.0), (0.05, 0.6), (-0.4, -0.5), (0.3, -0.3)])
def test_a_target_outside_the_polygon_gives_the_nearest_feasible_point(target):
    feet = both_feet()
    r = distribute_zmp_to_feet(np.array(target), MG, feet, 0.5)
    expected = projection_by_nnls(np.array(target), np.vstack([foot.vertices_world for foot in feet]))
    assert r.projected
    assert np.allclose(r.zmp_world_xy, expected, atol=1e-6)
    assert np.allclose(zmp_of(r), expected, atol=1e-6)
    assert np.concatenate(r.vertex_fz_n).min() >= -1e-6
    assert abs(r.fz_n.sum() - MG) <= 1e-6 * MG


def test_a_target_ahead_of_the_feet_lands_on_the_front_edge():
    r = distribute_zmp_to_feet(np.array([0.4, 0.02]), MG, both_feet(), 0.5)
    assert np.allclose(r.zmp_world_xy, [FRONT, 0.02], atol=1e-12)


def test_alpha_one_puts_almost_all_force_on_the_right_foot_when_the_zmp_allows_it():
    r = distribute_zmp_to_feet(np.array([0.01, -0.08]), MG, both_feet(), alpha=1.0)
    assert r.fz_n[0] > 0.999 * MG
    assert r.fz_n[1] < 1e-3 * MG


def test_alpha_zero_puts_almost_all_force_on_the_left_foot_when_the_zmp_allows_it():
    r = distribute_zmp_to_feet(np.array([0.0, 0.09]), MG, both_feet(), alpha=0.0)
    assert r.fz_n[1] > 0.999 * MG


def test_alpha_shifts_load_toward_the_right_foot_monotonically():
    zmp = np.array([0.0, 0.0])
    right_share = [distribute_zmp_to_feet(zmp, MG, both_feet(), a).fz_n[0] / MG for a in (0.2, 0.5, 0.8)]
    assert right_share[0] < right_share[1] < right_share[2]
    assert right_share[1] == pytest.approx(0.5, abs=1e-6)


def test_single_support_realises_a_zmp_inside_the_foot_and_projects_one_outside():
    foot = [rect_foot(RFOOT)]
    r = distribute_zmp_to_feet(np.array([0.05, -0.12]), MG, foot, alpha=0.3)
    assert r.fz_n.shape == (1,)
    assert r.fz_n[0] == pytest.approx(MG, rel=1e-6)
    assert np.allclose(r.cop_world_xy[0], [0.05, -0.12], atol=1e-6)
    out = distribute_zmp_to_feet(np.array([0.05, 0.1]), MG, foot)
    assert out.projected
    assert np.allclose(out.cop_world_xy[0], [0.05, -0.1 + HALF_WIDTH], atol=1e-6)


@pytest.mark.parametrize("target", [(0.02, 0.0), (0.1, -0.05), (-0.09, 0.15), (0.6, 0.6)])
def test_each_foot_cop_from_eq_12_to_14_lies_inside_its_own_foot(target):
    feet = [rect_foot(RFOOT, (0.02, 0.01)), rect_foot(LFOOT, (-0.01, 0.0))]
    r = distribute_zmp_to_feet(np.array(target), MG, feet, 0.5)
    for i, foot in enumerate(feet):
        f = r.vertex_fz_n[i]
        d = foot.vertices_world - foot.cop_ref_xy
        assert r.fz_n[i] == pytest.approx(f.sum(), abs=1e-9)
        assert r.n_xy_nm[i] == pytest.approx([-(d[:, 1] @ f), d[:, 0] @ f], abs=1e-9)
        if r.fz_n[i] > 1e-6 * MG:
            assert inside(r.cop_world_xy[i], foot.vertices_world)


def test_cop_weight_pulls_each_foot_cop_to_its_reference():
    feet = [rect_foot(RFOOT, (0.03, 0.0)), rect_foot(LFOOT, (0.03, 0.0))]
    r = distribute_zmp_to_feet(np.array([0.03, 0.0]), MG, feet, 0.5)
    assert np.allclose(r.cop_world_xy, [[0.03, -0.1], [0.03, 0.1]], atol=1e-6)
    assert np.allclose(r.n_xy_nm, 0.0, atol=1e-4)


def test_a_prebuilt_qp_solves_many_targets_and_its_outputs_are_read_only():
    qp = ForceDistributionQP(both_feet(), 0.5)
    for target in TARGETS_INSIDE.values():
        assert np.allclose(zmp_of(qp.solve(np.array(target), MG)), target, atol=1e-6)
    r = qp.solve(np.zeros(2), MG)
    with pytest.raises(ValueError):
        r.fz_n[0] = 0.0
    assert "alpha=0.500" in repr(qp)


@pytest.mark.filterwarnings("ignore:Converted matrix")
@pytest.mark.parametrize("solver", ["daqp", "clarabel"])
def test_the_exact_solvers_agree_with_daqp(solver):
    target = np.array([0.02, -0.03])
    ref = distribute_zmp_to_feet(target, MG, both_feet(), 0.7)
    r = distribute_zmp_to_feet(target, MG, both_feet(), 0.7, ForceDistributionWeights(solver=solver))
    assert np.allclose(r.fz_n, ref.fz_n, atol=1e-3)
    assert np.allclose(zmp_of(r), target, atol=1e-6)


def test_alpha_from_zmp_is_the_right_foot_share_along_the_feet_segment():
    assert alpha_from_zmp(RFOOT, RFOOT, LFOOT) == 1.0
    assert alpha_from_zmp(LFOOT, RFOOT, LFOOT) == 0.0
    assert alpha_from_zmp(np.array([0.05, 0.05]), RFOOT, LFOOT) == pytest.approx(0.25)
    assert alpha_from_zmp(np.array([0.0, -0.5]), RFOOT, LFOOT) == 1.0
    assert alpha_from_zmp(np.zeros(2), RFOOT, RFOOT) == 0.5


def test_invalid_inputs_are_refused_with_what_would_have_worked():
    with pytest.raises(InvalidCommand, match=r"\[0, 1\]"):
        ForceDistributionQP(both_feet(), alpha=1.5)
    with pytest.raises(InvalidCommand, match="1 \\(single support\\) or 2"):
        ForceDistributionQP(both_feet() * 2)
    with pytest.raises(InvalidCommand, match=r"\(n>=3, 2\)"):
        FootPolygon(np.zeros((2, 2)), np.zeros(2))
    with pytest.raises(InvalidCommand, match="allowed"):
        ForceDistributionWeights(solver="qpoases")
    with pytest.raises(InvalidCommand, match=">= 0"):
        distribute_zmp_to_feet(np.zeros(2), -1.0, both_feet())
    assert "daqp" in QP_SOLVERS


def test_changing_alpha_on_a_built_qp_gives_the_same_answer_as_a_new_qp():
    from controller.balance.force_distribution import ForceDistributionQP

    qp = ForceDistributionQP(both_feet(), 0.5)
    for alpha in (0.1, 0.5, 0.9):
        qp.set_alpha(alpha)
        reused = qp.solve(np.array([0.01, -0.02]), MG)
        fresh = ForceDistributionQP(both_feet(), alpha).solve(np.array([0.01, -0.02]), MG)
        assert np.allclose(reused.fz_n, fresh.fz_n, atol=1e-9)
        assert np.allclose(reused.n_xy_nm, fresh.n_xy_nm, atol=1e-9)


def test_a_target_projected_onto_the_edge_between_two_far_apart_heels_is_still_distributed():
    """Measured in a sideways emergency step: the feet 0.45 m apart, a ZMP target beyond the edge from the right
    heel to the left heel, alpha 0 (the right foot's weight 1e6 times the left's) while the target needs the right
    foot's load: daqp found no forces (a controller fault); the fallback solver distributes them."""
    right = np.array([[-0.0841096, -0.174], [0.1330904, -0.174], [0.1330904, -0.036], [-0.0841096, -0.036]])
    left = np.array([[-0.0763037, 0.2744397], [0.1408963, 0.2744397], [0.1408963, 0.4124397],
                     [-0.0763037, 0.4124397]])
    qp = ForceDistributionQP([FootPolygon(right, right.mean(axis=0)), FootPolygon(left, left.mean(axis=0))])
    qp.set_alpha(0.0)
    for target in ((-0.0780, 0.35), (-0.0774, 0.3515), (-0.09, 0.1)):
        forces = qp.solve(np.array(target), 560.0)
        assert forces.projected
        assert forces.fz_n.sum() == pytest.approx(560.0)
        assert forces.fz_n[0] > 1.0  # the right foot carries its share
        assert all((fs >= 0.0).all() for fs in forces.vertex_fz_n)
        # the realised ZMP is on the edge: the nearest point of the hull
        on_edge = np.array((-0.0841096, -0.036)) + np.array((0.0078059, 0.4484397)) * (
            (target[1] + 0.036) / 0.4484397)
        assert np.linalg.norm(forces.zmp_world_xy - on_edge) < 1e-3
