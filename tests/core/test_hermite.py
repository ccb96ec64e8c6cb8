"""GERBSInterpolator: partition of unity, Hermite interpolation, reproduction,
order independence, on random point sets in n = 1, 2, 3 and all covers/bases."""
import numpy as np
import pytest
from scipy.spatial import Delaunay

from gerbs_core import GERBSInterpolator

RNG = np.random.default_rng(12345)


def poly2(p):
    """A full quadratic in n variables with exact gradient and Hessian."""
    n = p.shape[-1]
    a = np.arange(1, n + 1) * 0.7
    Q = np.full((n, n), 0.3) + np.diag(np.arange(1, n + 1))
    v = 0.5 + p @ a + 0.5 * np.einsum("...i,ij,...j->...", p, Q, p)
    return v, a + p @ Q, np.broadcast_to(Q, p.shape[:-1] + (n, n))


def smooth(p):
    """sin/exp test function with exact derivatives (any n)."""
    s = p.sum(-1)
    v = np.sin(2 * s) + np.exp(p[..., 0])
    n = p.shape[-1]
    g = np.repeat((2 * np.cos(2 * s))[..., None], n, -1)
    g[..., 0] += np.exp(p[..., 0])
    H = np.repeat(np.repeat((-4 * np.sin(2 * s))[..., None, None], n, -2), n, -1)
    H[..., 0, 0] += np.exp(p[..., 0])
    return v, g, H


CASES = [
    (1, "balls", "general"),
    (2, "balls", "general"),
    (3, "balls", "general"),
    (2, "delaunay", "minimal"),
    (2, "delaunay", "maximal"),
    (2, "delaunay", "general"),
    (2, "voronoi", "minimal"),
    (2, "voronoi", "general"),
]
NPTS = {1: 15, 2: 40, 3: 40}


def _setup(n, cover, basis, func=smooth, N=None):
    N = N or NPTS[n]
    P = RNG.random((N, n))
    v, g, H = func(P)
    interp = GERBSInterpolator(P, v, g, H, cover=cover, basis=basis)
    return P, interp


def _samples(interp, n, M=400):
    x = RNG.random((M, n))
    return x


@pytest.mark.parametrize("n,cover,basis", CASES)
def test_partition_of_unity_and_bounds(n, cover, basis):
    P, interp = _setup(n, cover, basis)
    x = np.concatenate([_samples(interp, n), P])
    idx, B, Bg, Bh = interp.basis(x, nu=2)
    ok = np.all(np.isfinite(B), axis=1)
    assert ok.sum() > 0.5 * len(x)
    assert np.max(np.abs(B[ok].sum(1) - 1.0)) <= 1e-14
    assert B[ok].min() >= 0.0 and B[ok].max() <= 1.0
    # derivatives of the partition of unity vanish (relative to their size)
    gs = np.abs(Bg[ok]).max()
    hs = np.abs(Bh[ok]).max()
    assert np.abs(Bg[ok].sum(1)).max() <= 1e-11 * max(gs, 1)
    assert np.abs(Bh[ok].sum(1)).max() <= 1e-11 * max(hs, 1)


@pytest.mark.parametrize("n,cover,basis", CASES)
def test_hermite_interpolation_values_gradients_hessians(n, cover, basis):
    P, interp = _setup(n, cover, basis)
    v, g, H = smooth(P)
    for nu, ref in ((0, v), (1, g), (2, H)):
        got = interp(P, nu=nu)
        assert np.max(np.abs(got - ref)) <= 1e-10 * max(1.0, np.abs(ref).max())


@pytest.mark.parametrize("n,cover,basis", CASES)
def test_reproduces_quadratics_from_exact_data(n, cover, basis):
    P, interp = _setup(n, cover, basis, func=poly2)
    x = _samples(interp, n)
    # rounding scale: cancellation in sum_i D^nu(B_i T_i) grows with |D^nu B|
    _, B, Bg, Bh = interp.basis(x, nu=2)
    fin = np.isfinite(B).all(1)
    scale = [1.0, 1.0 + np.abs(Bg[fin]).sum(1).max(), 1.0 + np.abs(Bh[fin]).sum(1).max()]
    for nu in (0, 1, 2):
        got = interp(x, nu=nu)
        ok = np.isfinite(got.reshape(len(x), -1)).all(1)
        ref = poly2(x)[nu]
        assert ok.sum() > 0.5 * len(x)
        assert np.max(np.abs(got[ok] - ref[ok])) <= 1e-13 * scale[nu] * max(1.0, np.abs(poly2(x)[0]).max())


@pytest.mark.parametrize("n", [1, 2, 3])
def test_values_only_reproduces_polynomials_of_fit_degree(n):
    P = RNG.random((60 if n < 3 else 120, n))
    c = RNG.normal(size=n)

    def cubic(p):
        s = p @ c
        return 1 + s - 0.5 * s ** 2 + 0.25 * s ** 3 + p[..., 0] ** 2 * p[..., -1]

    interp = GERBSInterpolator(P, cubic(P), degree=3, cover="balls" if n != 2 else "delaunay")
    x = RNG.random((300, n))
    got = interp(x)
    ok = np.isfinite(got)
    assert ok.sum() > 100
    # normal equations: rounding ~ eps * cond(G) ~ 1e-9 for cubics in n = 3
    assert np.max(np.abs(got[ok] - cubic(x[ok]))) <= 1e-8


@pytest.mark.parametrize("n,cover,basis", [(2, "delaunay", "minimal"), (2, "voronoi", "minimal"),
                                           (2, "delaunay", "general"), (3, "balls", "general")])
def test_order_independence(n, cover, basis):
    """Remark 13 / Corollary 2: permuting the points permutes the basis."""
    P, interp = _setup(n, cover, basis)
    perm = RNG.permutation(len(P))
    v, g, H = smooth(P)
    other = GERBSInterpolator(P[perm], v[perm], g[perm], H[perm], cover=cover, basis=basis)
    x = _samples(interp, n, 200)
    B1 = interp.basis_matrix(x)
    B2 = other.basis_matrix(x)
    ok = np.isfinite(B1).all(1)
    assert np.array_equal(ok, np.isfinite(B2).all(1))
    assert np.max(np.abs(B1[ok][:, perm] - B2[ok])) <= 1e-13
    f1, f2 = interp(x, nu=2), other(x, nu=2)
    assert np.max(np.abs(f1[ok] - f2[ok])) <= 1e-10 * np.abs(f1[ok]).max()


def test_vector_valued_data_and_shapes():
    P = RNG.random((30, 2))
    vals = np.stack([smooth(P)[0], 2 * smooth(P)[0], P[:, 0]], -1).reshape(30, 3, 1)
    interp = GERBSInterpolator(P, vals)
    x = RNG.random((4, 5, 2)) * 0.5 + 0.25
    assert interp(x).shape == (4, 5, 3, 1)
    assert interp(x, nu=1).shape == (4, 5, 3, 1, 2)
    assert interp(x, nu=2).shape == (4, 5, 3, 1, 2, 2)
    # components are interpolated independently: linear in the data
    single = GERBSInterpolator(P, vals[:, 1, 0])
    assert np.allclose(interp(x)[..., 1, 0], single(x), rtol=0, atol=1e-13)
    np.testing.assert_allclose(interp(P), vals, atol=1e-13)


def test_fill_value_outside_domain():
    P = RNG.random((30, 2))
    interp = GERBSInterpolator(P, smooth(P)[0], fill_value=-7.0)
    x = np.array([[5.0, 5.0], [-1.0, 0.5]])
    assert np.all(interp(x) == -7.0)
    assert np.all(interp(x, nu=1) == -7.0)
    nan_interp = GERBSInterpolator(P, smooth(P)[0])
    assert np.all(np.isnan(nan_interp(x)))


def test_derivatives_match_finite_differences():
    """nu=1, 2 are the derivatives of nu=0, nu=1 (checked by central differences)."""
    for cover, basis, n in (("delaunay", "minimal", 2), ("balls", "general", 3)):
        P = RNG.random((40, n))
        interp = GERBSInterpolator(P, smooth(P)[0], cover=cover, basis=basis)
        x = 0.3 + 0.4 * RNG.random((30, n))
        h = 1e-6
        g, H = interp(x, 1), interp(x, 2)
        for k in range(n):
            e = np.zeros(n)
            e[k] = h
            fd = (interp(x + e) - interp(x - e)) / (2 * h)
            fdg = (interp(x + e, 1) - interp(x - e, 1)) / (2 * h)
            ok = np.isfinite(fd)
            assert np.max(np.abs(fd[ok] - g[ok, k])) <= 1e-5 * max(1, np.abs(g).max())
            assert np.max(np.abs(fdg[ok] - H[ok, :, k])) <= 1e-4 * max(1, np.abs(H[ok]).max())


def test_regularized_taylor_coefficients_lemma5():
    """Averaged Taylor polynomials over B(x_i, rho_i) (Lemma 5, Theorem 3): exact for
    quadratics (degree 2), a quasi-interpolant otherwise (values at x_i off by O(rho^3))."""
    P = RNG.random((40, 2))

    def jet(func):
        def f_jet(y):
            v, g, H = func(y)
            return [v[..., None], g[..., None, :], H[..., None, :, :]]
        return f_jet

    for cover, basis in (("delaunay", "minimal"), ("balls", "general")):
        quad = GERBSInterpolator(P, poly2(P)[0], cover=cover, basis=basis, degree=2, regularized=jet(poly2))
        x = RNG.random((200, 2)) * 0.5 + 0.25
        got = quad(x)
        ok = np.isfinite(got)
        assert np.max(np.abs(got[ok] - poly2(x[ok])[0])) <= 1e-12
        sm = GERBSInterpolator(P, smooth(P)[0], cover=cover, basis=basis, degree=2, regularized=jet(smooth))
        err = np.abs(sm(P) - smooth(P)[0])
        assert 0 < err.max() <= 50 * sm.rho.max() ** 3
    with pytest.raises(Exception, match="degree"):
        GERBSInterpolator(P, smooth(P)[0], regularized=jet(smooth))


def test_chunked_and_spatially_ordered_evaluation_is_identical():
    """Chunking (bounded memory) and the cell-by-cell visiting order of large queries
    do not change the result."""
    P = RNG.random((200, 2))
    v = smooth(P)[0]
    whole = GERBSInterpolator(P, v, chunk_size=10 ** 6)
    small = GERBSInterpolator(P, v, chunk_size=37)
    x = RNG.random((1000, 2))
    assert small._spatial_order(x) is not None
    for nu in (0, 1, 2):
        np.testing.assert_array_equal(small(x, nu), whole(x, nu))


@pytest.mark.parametrize("metric", ["euclidean", "linf", "l1", "bounded", 3.0, 1.5, 0.5])
def test_ball_covers_in_every_metric(metric):
    """General construction (32) with the bumps of section 2.5.1: partition of unity
    and Hermite interpolation up to the order the metric's smoothness allows."""
    from gerbs_core.scattered.metric_forms import as_metric
    P = RNG.random((40, 2))
    v, g, H = smooth(P)
    interp = GERBSInterpolator(P, v, g, H, cover="balls", metric=metric)
    x = RNG.random((300, 2))
    x = np.concatenate([x[Delaunay(P).find_simplex(x) >= 0], P])     # the certified domain
    Bm = interp.basis_matrix(x)
    ok = np.isfinite(Bm).all(1)
    assert ok.all() and interp.cover_guaranteed == as_metric(metric, 2).convex
    assert np.max(np.abs(Bm.sum(1) - 1)) <= 1e-14 and Bm.min() >= 0
    nu_max = as_metric(metric, 2).max_nu
    for nu, ref in list(zip((0, 1, 2), (v, g, H)))[: nu_max + 1]:
        np.testing.assert_allclose(interp(P, nu), ref, rtol=0, atol=1e-10 * np.abs(ref).max())
    if nu_max < 2:
        with pytest.raises(Exception, match="nu"):
            interp(P, nu_max + 1)


def test_scalar_values_sum_is_einsums_bit_for_bit():
    """local_sums' term-by-term values sum (V = 1) equals the einsum it replaces to the
    last bit, for several candidate counts K, monomial counts Q and chunk sizes, with
    zero weights (empty slots) and coefficients / monomials over 16 decades."""
    from gerbs_core.scattered.local_sums import _values_scalar
    rng = np.random.default_rng(5)
    for N, M, K, Q in [(50, 1, 3, 10), (4004, 20000, 3, 10), (300, 5000, 20, 6), (300, 4099, 5, 3),
                       (10, 3, 1, 1)]:
        C0 = rng.normal(size=(N, 1, Q)) * 10.0 ** rng.integers(-8, 8, (N, 1, Q))
        j = rng.integers(0, N, (M, K))
        Bv = rng.random((M, K))
        Bv[rng.random((M, K)) < 0.3] = 0.0
        mono = rng.normal(size=(Q, K, M)) * 10.0 ** rng.integers(-5, 5, (Q, K, M))
        ref = np.einsum("mk,mkvq,mkq->mv", Bv, C0[j], np.ascontiguousarray(mono.transpose(2, 1, 0)))
        got = _values_scalar(Bv, np.ascontiguousarray(C0.transpose(2, 0, 1)),
                             np.ascontiguousarray(j.T), mono)
        np.testing.assert_array_equal(got, ref)
