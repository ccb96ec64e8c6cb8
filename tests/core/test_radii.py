"""Radii of the general construction: (16), (17), Remark 6, automatic R covering the hull."""
import numpy as np
import pytest

from gerbs_core.errors import InvalidParameterError, InvalidPointSetError
from gerbs_core.scattered.metrics import L1, Bounded, Euclidean, LInf, Lp, QuasiNorm
from gerbs_core.scattered.radii import (auto_R, auto_rho, check_points, nearest_distances, simplicialization,
                                        validate_radii)

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


def _hull_samples(P, simp, per=20):
    n = P.shape[1]
    lam = RNG.dirichlet(np.ones(n + 1) * 0.3, size=(len(simp), per))   # near faces and vertices too
    return np.einsum("tsk,tkn->tsn", lam, P[simp]).reshape(-1, n)


def _uncovered(P, R, m, x, margin=0.9):
    """Samples x with no point x_j at distance <= margin R_j (base norm), brute force."""
    Rb = m.base_radius(R)
    d = m.base.norm(x[:, None, :] - P[None, :, :])
    return int((~np.any(d <= margin * Rb[None, :] * (1 + 1e-12), axis=1)).sum())


@pytest.mark.parametrize("n", [1, 2, 3])
def test_auto_R_covers_the_hull_with_margin(n):
    """The automatic radii are certified: every point of the hull is within 0.9 R_j of
    some x_j (so psi_j >= b(0.9) there, Definition 11), checked by brute force on
    samples of every simplex. The radii are local: R_i / (local spacing) is bounded
    (no long hull edge inflates them) and sum_j [x in B_j] stays O(1)."""
    P = np.random.default_rng(n).random((150, n))
    simp = simplicialization(P)
    x = _hull_samples(P, simp, per=8)
    for m in (Euclidean(n), LInf(n), L1(n), Lp(n, 3.0), Bounded(Euclidean(n)), Euclidean(n, [2.0] * n)):
        R, guaranteed = auto_R(P, m)
        assert guaranteed, type(m).__name__
        assert _uncovered(P, R, m, x) == 0, type(m).__name__
        spacing = np.sort(m.base.norm(P[:, None] - P[None]), axis=1)[:, n + 1]
        ratio = m.base_radius(R) / spacing
        assert np.median(ratio) <= 3.0 and ratio.max() <= 12, (type(m).__name__, ratio.max())


def test_uncertified_radii_leave_holes_the_check_finds():
    """The control: the local-spacing radii before certification leave samples of the
    hull uncovered (so the test above can fail), and certify_cover repairs them by
    enlarging only some radii."""
    from scipy.spatial import cKDTree
    from gerbs_core.scattered.cover_check import certify_cover
    P = np.random.default_rng(5).random((150, 3))
    m = Euclidean(3)
    simp = simplicialization(P)
    x = _hull_samples(P, simp, per=8)
    spacing = np.sort(m.norm(P[:, None] - P[None]), axis=1)[:, 4]
    raw = 0.6 * spacing
    assert _uncovered(P, raw, m, x) > 0
    fixed, n_enlarged = certify_cover(P, simp, raw, m, cKDTree(P))
    assert _uncovered(P, fixed, m, x) == 0
    assert 0 < n_enlarged < len(P) and np.all(fixed >= raw)


def test_quasi_norm_radii_are_not_claimed_certified():
    P = RNG.random((50, 2))
    R, guaranteed = auto_R(P, QuasiNorm(2, 0.5))
    assert not guaranteed and np.all(R > 0)


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


def test_duplicates_match_a_nearest_neighbour_search():
    """check_points' lexicographic duplicate search flags exactly the points at
    distance 0 from another one (groups of any size, -0.0 == 0.0)."""
    from scipy.spatial import cKDTree
    from gerbs_core.scattered.radii import _duplicates
    P = np.random.default_rng(2).integers(0, 25, (3000, 3)).astype(float)
    d = cKDTree(P).query(P, k=2)[0][:, 1]
    assert np.array_equal(_duplicates(P), np.flatnonzero(d == 0.0))
    assert _duplicates(np.array([[0.0, 1.0], [2.0, 2.0], [-0.0, 1.0]])).tolist() == [0, 2]
