"""Radii of the general construction: (16), (17), Remark 6, automatic R covering the hull."""
import numpy as np
import pytest

from gerbs_core.errors import InvalidParameterError, InvalidPointSetError
from gerbs_core.scattered.metrics import L1, Bounded, Euclidean, LInf, Lp, QuasiNorm
from gerbs_core.scattered.radii import auto_R, auto_rho, check_points, nearest_distances, validate_radii
from scipy.spatial import Delaunay

RNG = np.random.default_rng(11)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_nearest_distances_match_brute_force(n):
    P = RNG.random((60, n))
    w = 0.5 + RNG.random(n)
    for m in (Euclidean(n), Euclidean(n, w), Lp(n, 3.0, w), LInf(n), L1(n, w), QuasiNorm(n, 0.5),
              QuasiNorm(n, 0.6, w), Bounded(L1(n))):
        D = m.norm(P[:, None, :] - P[None, :, :])
        np.fill_diagonal(D, np.inf)
        np.testing.assert_allclose(nearest_distances(P, m), D.min(1), rtol=1e-13, err_msg=type(m).__name__)


def test_remark6_rho_gives_disjoint_phi_supports():
    """(34): with rho_i = half the nearest distance, no two phi balls overlap."""
    P = RNG.random((80, 2))
    for m in (Euclidean(2), LInf(2), L1(2)):
        rho = auto_rho(P, m)
        D = m.norm(P[:, None] - P[None])
        np.fill_diagonal(D, np.inf)
        assert np.all(rho[:, None] + rho[None, :] <= D * (1 + 1e-12))


@pytest.mark.parametrize("n", [1, 2, 3])
def test_auto_R_covers_the_hull_with_margin(n):
    """Every point of a Delaunay simplex is within 0.9 R_v of each vertex v, so the
    psi balls cover the hull and psi_v >= b(0.9) there (Definition 11)."""
    P = RNG.random((40, n))
    for m in (Euclidean(n), LInf(n), L1(n), Bounded(Euclidean(n))):
        R, guaranteed = auto_R(P, m)
        assert guaranteed
        if n == 1:
            order = np.argsort(P[:, 0])
            simp = np.stack([order[:-1], order[1:]], 1)
        else:
            simp = Delaunay(P).simplices
        lam = RNG.dirichlet(np.ones(n + 1), size=(len(simp), 10))
        x = np.einsum("tsk,tkn->tsn", lam, P[simp])
        d = m.norm(x[:, :, None, :] - P[simp][:, None, :, :])          # (T, s, n+1)
        Rv = R[simp][:, None, :]
        assert np.all(d < 0.9 * Rv + 1e-12 if not isinstance(m, Bounded) else d < Rv)


def test_check_points_errors_name_indices():
    P = RNG.random((10, 2))
    P[7] = P[2]
    with pytest.raises(InvalidPointSetError, match="duplicate") as ei:
        check_points(P)
    assert set(ei.value.indices) == {2, 7}
    P = RNG.random((10, 2))
    P[4, 1] = np.nan
    with pytest.raises(InvalidPointSetError, match="non-finite") as ei:
        check_points(P)
    assert ei.value.indices == (4,)
    with pytest.raises(InvalidParameterError, match="shape"):
        check_points(np.zeros((3, 2, 2)))
    with pytest.raises(InvalidPointSetError, match="at least"):
        check_points(np.zeros((0, 2)), min_points=1)
    # the caller's array is not modified and not aliased
    Q = RNG.random((5, 2))
    out = check_points(Q)
    out[0] = 99
    assert Q[0, 0] != 99


def test_validate_radii_constraints_16_17():
    P = RNG.random((20, 2))
    d = nearest_distances(P, Euclidean(2))
    validate_radii(0.5 * d, d, d)
    bad = 0.5 * d
    bad[[3, 5]] = 1.5 * d[[3, 5]]
    with pytest.raises(InvalidParameterError, match=r"\(16\).*\[3, 5\]"):
        validate_radii(bad, 2 * d, d)
    with pytest.raises(InvalidParameterError, match=r"\(17\).*\[0\]"):
        R = d.copy()
        R[0] = 0.1 * d[0]
        validate_radii(0.5 * d, R, d)
    with pytest.raises(InvalidParameterError, match="> 0"):
        validate_radii(-d, d, d)
