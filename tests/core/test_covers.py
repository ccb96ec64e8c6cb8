"""Planar star covers: supports inside the cover elements, smooth gauge (no jumps
across the spokes of a Delaunay star, while the kinked exact radius is flagged),
thickness diagnostics, Voronoi and user-polygon covers."""
import numpy as np
import pytest

from gerbs_core import GERBSInterpolator
from gerbs_core.scattered.diagnostics import cover_report

RNG = np.random.default_rng(7)


def f(p):
    return np.sin(3 * p[..., 0]) * np.cos(2 * p[..., 1]) + p[..., 0] ** 3


def _extrapolation_weights(n):
    """w (n,) with w @ [p(1), ..., p(n)] = p(0) for polynomials of degree < n."""
    V = np.vander(np.arange(1, n + 1, dtype=float), n, increasing=True)
    return np.linalg.solve(V.T, np.eye(n)[0])


def spoke_jumps(interp, i, h=1e-4, n=7, fracs=(0.3, 0.6, 0.9)):
    """Largest relative jumps of the one-sided first and second derivatives of psi_i
    and of the interpolant across every spoke of the star of vertex i (the spokes
    between two of its triangles; the open ends of a hull star are not spokes).

    One-sided limits: the analytic derivatives at distance h, 2h, ..., n h on each
    side of the spoke (at fracs of rho~ along it), extrapolated to the spoke by the
    degree n-1 polynomial through them (error O(h^n) times the n-th derivative
    across the spoke; n = 7 because ERBS's high derivatives are large, as in
    tests/core/test_surface_smoothness.fd_jumps). Relative to the derivative scale
    of the star (max over all its samples), not to the local magnitude, which
    vanishes where psi_i flattens out (ERBS is flat at 0 and 1)."""
    cov = interp.cover
    W = _extrapolation_weights(n)
    jumps, scale = np.zeros(4), np.zeros(4)
    for e in np.flatnonzero((cov.edge_star == i) & (cov.prev_edge >= 0)):
        rk = cov.rho_tilde(np.array([e]), np.array([0.0]))[0][0]
        d = cov.a0[e] / np.linalg.norm(cov.a0[e])
        nrm = np.array([-d[1], d[0]])
        s = np.concatenate([np.arange(1, n + 1), -np.arange(1, n + 1)]) * h
        for fr in fracs:
            pts = cov.centers[i] + fr * rk * d + s[:, None] * nrm
            _, g, H = cov.psi_jet(pts, np.full((2 * n, 1), i), None, 2)
            for k, a in enumerate((g[:, 0], H[:, 0], interp(pts, 1), interp(pts, 2))):
                lim_p = np.tensordot(W, a[:n], 1)
                lim_m = np.tensordot(W, a[n:], 1)
                jumps[k] = max(jumps[k], np.abs(lim_p - lim_m).max())
                scale[k] = max(scale[k], np.abs(a).max())
    return jumps / np.maximum(scale, 1e-300)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_no_jump_across_spokes_and_kinked_gauge_is_flagged(seed):
    """Issue 3: on the UNIT square (12 random points, Delaunay stars; every vertex,
    hull stars included), psi_i and the interpolant have no jump of their first
    and second derivatives across the spokes at step h = 1e-4 (relative <= 1e-6);
    the same test flags the kinked exact polygon radius."""
    rng = np.random.default_rng(seed)
    P = rng.random((12, 2))
    smooth = GERBSInterpolator(P, f(P))
    kinked = GERBSInterpolator(P, f(P), exact_gauge=True)
    js = np.max([spoke_jumps(smooth, i) for i in range(len(P))], axis=0)
    jk = np.max([spoke_jumps(kinked, i) for i in range(len(P))], axis=0)
    print(f"spoke jumps seed {seed}: psi d1 {js[0]:.1e} d2 {js[1]:.1e}, interpolant d1 "
          f"{js[2]:.1e} d2 {js[3]:.1e}; kinked {np.array2string(jk, precision=2)}")
    assert np.all(js <= 1e-6), js
    # psi_i of the exact polygon radius has kinks: first and second derivatives jump,
    # for psi_i and (damped by the normalization and the smooth data) for the interpolant
    assert jk[0] > 1e-1 and jk[1] > 1e-1, jk
    assert jk[2] > 1e-3 and jk[3] > 1e-2, jk


def test_support_inside_star_and_envelope_below_radius():
    P = RNG.random((40, 2))
    interp = GERBSInterpolator(P, f(P))
    cov = interp.cover
    # rho~ <= shrink * rho at many angles on every edge (DESIGN 4: supp psi_i in Omega_i)
    E = len(cov.delta)
    t = RNG.random((E, 20)) * cov.delta[:, None]
    e = np.repeat(np.arange(E)[:, None], 20, 1)
    rt = cov.rho_tilde(e.ravel(), t.ravel())[0]
    rho = cov.p[e.ravel()] / np.cos(t.ravel() - cov.nu[e.ravel()])
    assert np.all(rt <= cov.shrink * rho * (1 + 1e-12))
    assert cov.kappa * (1 - 1e-12) <= cov.measured_kappa() <= 1
    # psi_i vanishes on and outside the boundary of the star polygon of x_i
    for i in range(len(P)):
        es = np.flatnonzero(cov.edge_star == i)
        q = cov.centers[i] + cov.a0[es]
        q1 = cov.centers[i] + cov.a1[es]
        lam = RNG.random((len(es), 5, 1))
        bnd = (q[:, None] * (1 - lam) + q1[:, None] * lam).reshape(-1, 2)
        for scale in (1.0, 1.05):
            x = cov.centers[i] + scale * (bnd - cov.centers[i])
            v = cov.psi_jet(x, np.full((len(x), 1), i), None, 0)[0]
            assert np.all(v == 0.0)
        # and is positive near its point
        near = cov.centers[i] + 1e-3 * (bnd[:5] - cov.centers[i])
        assert np.all(cov.psi_jet(near, np.full((5, 1), i), None, 0)[0] > 0.99)


@pytest.mark.parametrize("cover", ["delaunay", "voronoi"])
def test_thickness_reported_positive(cover):
    P = RNG.random((50, 2)) * 0.9 + 0.05
    interp = GERBSInterpolator(P, f(P), cover=cover)
    rep = cover_report(interp, resolution=5)
    assert rep["outside"] == 0
    assert rep["eps0"] > 1e-6
    assert rep["condition"] < 1e6 and rep["condition"] == pytest.approx(1 / rep["min_sum"])
    assert 1 <= rep["max_overlap"] <= len(P)
    # the kinked cover with the same shrink is no thicker than itself: sanity on eps0 definition
    assert rep["eps0"] <= 1.0


def test_voronoi_cover_is_minimally_supported():
    """Doubled Voronoi cells: no other site lies in the interior of supp psi_i, so the
    minimal basis B = Psi interpolates (Theorem 6)."""
    P = RNG.random((30, 2)) * 0.8 + 0.1
    interp = GERBSInterpolator(P, f(P), cover="voronoi")
    idx, B, _, _ = interp.basis(P)
    Bm = interp.basis_matrix(P)
    assert np.allclose(Bm, np.eye(len(P)), atol=0, rtol=0)
    # and it covers the whole domain square
    lo, hi = interp.domain.min(0), interp.domain.max(0)
    g = np.stack(np.meshgrid(np.linspace(lo[0], hi[0], 40), np.linspace(lo[1], hi[1], 40)), -1).reshape(-1, 2)
    assert np.all(np.isfinite(interp(g)))
    assert np.all(np.isnan(interp(np.array([[lo[0] - 1e-3, 0.5], [0.5, hi[1] + 1e-3]]))))


def test_user_polygons():
    """Squares around grid points (star-shaped, overlapping): partition of unity,
    support inside each polygon, Hermite interpolation."""
    xs = np.linspace(0, 1, 4)
    P = np.stack(np.meshgrid(xs, xs), -1).reshape(-1, 2)
    sq = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    x = RNG.random((500, 2))
    # half-width 0.3 < spacing 1/3: minimally supported, B = Psi interpolates (Theorem 6)
    # half-width 0.55: other points inside, the general basis (32) is needed (Theorem 2)
    for half, basis in ((0.3, "minimal"), (0.3, "maximal"), (0.55, "general")):
        interp = GERBSInterpolator(P, f(P), cover=[p + half * sq for p in P], basis=basis)
        Bm = interp.basis_matrix(x)
        ok = np.isfinite(Bm).all(1)
        assert ok.all()
        assert np.max(np.abs(Bm.sum(1) - 1)) <= 1e-14
        outside = np.abs(x[:, None, :] - P[None]).max(-1) >= half
        assert np.all(Bm[outside] == 0)
        np.testing.assert_allclose(interp(P), f(P), rtol=0, atol=1e-14)
    # B = Psi on a cover that is not minimally supported does not interpolate
    bad = GERBSInterpolator(P, f(P), cover=[p + 0.55 * sq for p in P], basis="minimal")
    assert np.abs(bad(P) - f(P)).max() > 1e-3
    with pytest.raises(ValueError, match="star-shaped"):
        GERBSInterpolator(P, f(P), cover=[p + 0.3 * sq[::-1] for p in P])     # clockwise


@pytest.mark.parametrize("n", [1, 2, 3])
def test_ball_cover_supports_and_guaranteed_thickness(n):
    """cover='balls': supp B_i inside B(x_i, R_i); the automatic R gives
    eps0 >= b(0.9) on the hull (radii.auto_R)."""
    from gerbs_core.kernels import ERBS
    P = RNG.random((30, n))
    interp = GERBSInterpolator(P, f(np.pad(P, ((0, 0), (0, max(0, 2 - n))))), cover="balls")
    rep = cover_report(interp, resolution=4)
    assert rep["outside"] == 0
    assert rep["eps0"] >= ERBS().bump(0.9) * (1 - 1e-12)
    x = RNG.random((300, n))
    Bm = interp.basis_matrix(x)
    d = np.linalg.norm(x[:, None, :] - P[None], axis=-1)
    ok = np.isfinite(Bm).all(1)
    assert np.all(Bm[ok][d[ok] >= interp.R[None, :]] == 0)


def test_batched_exact_gauge_matches_gauge_module():
    """The batched planar gauge (covers.PlanarStarCover) and gauge.StarGauge compute
    the same psi, gradient and Hessian for the exact polygon radius."""
    from gerbs_core.scattered.covers import polygon_cover
    from gerbs_core.gauge.star import StarGauge
    from gerbs_core.kernels import ERBS
    c = np.array([[0.1, 0.2]])
    ang = np.sort(RNG.random(7)) * 2 * np.pi
    ring = c[0] + np.stack([np.cos(ang), np.sin(ang)], -1) * (0.5 + RNG.random((7, 1)))
    cov = polygon_cover(c, [ring], ERBS(), exact=True)
    sg = StarGauge.from_polygon(c[0], ring, exact=True)
    x = c[0] + RNG.normal(size=(2000, 2)) * 0.5
    for nu in (0, 1, 2):
        a = cov.psi_jet(x, np.zeros((2000, 1), int), None, nu)[nu][:, 0]
        b = sg.psi(x, nu)
        assert np.max(np.abs(a - b)) <= 1e-12 * np.abs(b).max()


def test_one_sided_limits_on_the_spokes_unit_square():
    """On the unit square, the exact one-sided limits at a spoke: the analytic jets of
    psi_i evaluated ON the spoke with the formulas of the two adjacent triangles
    (edges prev(e) and e). Equal for the GERBS envelope, different for the kink."""
    P = RNG.random((40, 2))
    for exact, expect_equal in ((False, True), (True, False)):
        cov = GERBSInterpolator(P, f(P), exact_gauge=exact).cover
        has_prev = np.flatnonzero(cov.prev_edge >= 0)
        e = has_prev
        q = cov.prev_edge[e]
        rk = cov.rho_tilde(e, np.zeros(len(e)))[0]
        x = cov.centers[cov.edge_star[e]] + 0.6 * rk[:, None] * cov.a0[e] / np.linalg.norm(cov.a0[e], axis=1)[:, None]
        star = cov.edge_star[e][:, None]
        right = cov.psi_jet(x, star, e[:, None], 2)
        left = cov.psi_jet(x, star, q[:, None], 2)
        for k in (1, 2):
            jump = np.abs(right[k] - left[k]).reshape(len(e), -1).max(1)
            size = np.abs(right[k]).reshape(len(e), -1).max(1)
            rel = jump / np.maximum(size, 1e-300)
            if expect_equal:
                assert rel.max() <= 1e-10
            else:
                assert np.median(rel) > 1e-2


def test_envelope_bounds_dense_on_a_large_cover():
    """kappa shrink rho <= rho~ <= shrink rho at 64 angles on every edge of the
    Delaunay stars of 2000 random points (thin hull triangles and nearly radial
    edges included): the transition widths are certified, not sampled."""
    from gerbs_core.scattered.covers import delaunay_cover
    from gerbs_core.kernels import ERBS
    P = np.random.default_rng(11).random((2000, 2))
    cov, _, _ = delaunay_cover(P, ERBS())
    E = len(cov.delta)
    e = np.repeat(np.arange(E), 64)
    t = np.tile(np.linspace(0.0, 1.0, 64), E) * cov.delta[e]
    ratio = cov.rho_tilde(e, t)[0] / (cov.shrink * cov.p[e] / np.cos(t - cov.nu[e]))
    # (rounding: rho = p / cos(t - nu) loses ~1e-11 relative on nearly radial edges,
    # where a reflex-only edge's line is used unscaled, c = 1)
    assert ratio.max() <= 1 + 1e-10 and ratio.min() >= cov.kappa * (1 - 1e-10)
    # one transition per corner, inside the two edges
    assert np.all(cov.L + cov.R <= cov.delta * (1 + 1e-12))
    assert np.all(cov.R[cov.next_edge >= 0] > 0) and np.all(cov.L[cov.prev_edge >= 0] > 0)


def test_vectorized_barycentric_transforms_match_scipy():
    """delaunay_triangulation fills scipy's transform cache itself: equal to scipy's own
    to rounding (relative to the inverse's size), same point location, NaN on a
    degenerate (zero-area) triangle."""
    from scipy.spatial import Delaunay
    from gerbs_core.scattered.covers import _set_transforms, delaunay_triangulation
    rng = np.random.default_rng(4)
    P = np.concatenate([rng.random((400, 2)), 0.5 + 1e-3 * rng.normal(size=(200, 2))])
    tri = delaunay_triangulation(P)[0]
    assert tri._transform is not None      # filled before any find_simplex (this scipy)
    ref = Delaunay(P).transform
    scale = np.abs(ref).max(axis=(1, 2), keepdims=True)
    assert np.max(np.abs(tri.transform - ref) / scale) < 1e-12
    X = rng.random((5000, 2)) * 1.2 - 0.1
    assert np.array_equal(tri.find_simplex(X, tol=1e-12), Delaunay(P).find_simplex(X, tol=1e-12))

    class Flat:                   # a zero-area triangle among good ones
        simplices = np.array([[0, 1, 2], [0, 1, 3]])
        _transform = None
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0]])
    _set_transforms(Flat, pts)
    assert np.isnan(Flat._transform[0]).all() and np.isfinite(Flat._transform[1]).all()
    # slivers: NaN exactly where scipy's own builder says so (its limit is 1000 eps)
    from scipy.spatial import _qhull
    for h in (1e-10, 1e-12, 1e-13, 1e-14, 1e-15, 1e-16):
        pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, h], [0.0, 1.0]])
        Flat._transform = None
        _set_transforms(Flat, pts)
        ref = _qhull._get_barycentric_transforms(pts, Flat.simplices.astype(np.intc), np.finfo(float).eps)
        assert np.array_equal(np.isnan(Flat._transform[:, 0, 0]), np.isnan(ref[:, 0, 0])), h


@pytest.mark.parametrize("cover", ["delaunay", "voronoi"])
def test_direct_envelope_formula_equals_the_row_tables(cover, monkeypatch):
    """Covers above ``planar_star._TABLE_EDGES`` edges evaluate u_tilde by the direct
    formula instead of the per-edge row tables; the two give the same bits (values,
    gradients, Hessians, NaN queries and points outside the hull included). The tests'
    covers are small, so the direct path is forced here by a threshold of 0."""
    import gerbs_core.scattered.planar_star as ps
    rng = np.random.default_rng(3)
    P = np.concatenate([rng.random((600, 2)), 0.5 + 0.05 * rng.standard_normal((300, 2))])
    Q = np.concatenate([rng.uniform(-0.1, 1.1, (3000, 2)), [[np.nan, 0.5], [0.5, np.nan]]])
    tabled = GERBSInterpolator(P, f(P), cover=cover)
    assert tabled.cover._sides is not None
    monkeypatch.setattr(ps, "_TABLE_EDGES", 0)
    direct = GERBSInterpolator(P, f(P), cover=cover)
    assert direct.cover._sides is None
    for nu in (0, 1, 2):
        a, b = tabled(Q, nu=nu), direct(Q, nu=nu)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
        assert np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("cover", ["delaunay", "voronoi", "balls"])
def test_non_finite_queries_give_nan_quietly_on_every_cover(cover):
    """A NaN or infinite query point gets the fill value (NaN) for values and
    derivatives, with no warning, on every cover; the finite queries beside it are
    unaffected (before 2026-12-02 the Voronoi and ball covers raised scipy's KD-tree
    error for the whole call)."""
    import warnings
    rng = np.random.default_rng(0)
    P = rng.random((300, 2))
    Q = np.array([[np.nan, 0.5], [0.5, np.inf], [-np.inf, np.nan], [0.5, 0.5], [0.3, 0.6]])
    interp = GERBSInterpolator(P, f(P), cover=cover)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for nu in (0, 1, 2):
            out = interp(Q, nu=nu)
            assert np.isnan(out[:3]).all()
            np.testing.assert_array_equal(out[3:], interp(Q[3:], nu=nu))
            assert np.isfinite(out[3:]).all()


@pytest.mark.parametrize("direct", [False, True])
def test_psi_values_without_cosines_equal_the_jet_path(direct, monkeypatch):
    """psi values (nu = 0) take the lines' gauges as y . line_vec (no cosines, no r);
    the derivative path's r u~(t) gives the same values to rounding, on the row tables
    and on the direct formula, outside the hull and on hull slivers included."""
    import gerbs_core.scattered.planar_star as ps
    if direct:
        monkeypatch.setattr(ps, "_TABLE_EDGES", 0)
    rng = np.random.default_rng(8)
    P = np.concatenate([rng.random((500, 2)), 0.3 + 0.02 * rng.standard_normal((300, 2)),
                        [[0, 0], [1, 0], [0, 1], [1, 1]]])
    interp = GERBSInterpolator(P, f(P))
    g = np.linspace(0.0, 1.0, 60)
    x = np.concatenate([np.stack(np.meshgrid(g, g), -1).reshape(-1, 2),
                        rng.uniform(-0.1, 1.1, (2000, 2))])
    idx, edge = interp._candidates(x)
    v0 = interp.cover.psi_jet(x, idx, edge, 0)[0]
    v1 = interp.cover.psi_jet(x, idx, edge, 1)[0]
    assert np.max(np.abs(v0 - v1)) <= 1e-12
