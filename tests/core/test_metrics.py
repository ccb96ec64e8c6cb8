"""Metrics of section 2.5.1 and their bumps: metric axioms, exact supports,
derivatives against finite differences, smoothness limits."""
import numpy as np
import pytest

from gerbs_core.errors import InvalidParameterError
from gerbs_core.kernels import ERBS
from gerbs_core.scattered.metric_forms import as_metric
from gerbs_core.scattered.metrics import L1, Bounded, Euclidean, LInf, Lp, QuasiNorm

K = ERBS()
RNG = np.random.default_rng(3)


def all_metrics(n):
    w = 0.5 + RNG.random(n)
    return [Euclidean(n), Euclidean(n, w), Lp(n, 3.0), Lp(n, 2.5, w), Lp(n, 1.5), LInf(n), LInf(n, w),
            L1(n), L1(n, w), QuasiNorm(n, 0.5), QuasiNorm(n, 0.7, w), Bounded(Euclidean(n)), Bounded(Lp(n, 3.0))]


@pytest.mark.parametrize("n", [1, 2, 3])
def test_metric_axioms(n):
    for m in all_metrics(n):
        x, y, z = RNG.normal(size=(3, 200, n))
        dxy, dyx = m.dist(x, y), m.dist(y, x)
        assert np.all(dxy > 0) and np.allclose(dxy, dyx, rtol=1e-14)
        assert np.all(m.dist(x, x) == 0)
        assert np.all(m.dist(x, z) <= dxy + m.dist(y, z) + 1e-12), type(m).__name__


@pytest.mark.parametrize("n", [1, 2, 3])
def test_bump_support_is_the_metric_ball(n):
    R = 0.7
    for m in all_metrics(n):
        y = RNG.normal(size=(4000, n)) * 0.5
        RR = 0.4 if isinstance(m, Bounded) else R
        v = m.bump_jet(y, np.full(len(y), RR), K)[0]
        d = m.norm(y)
        # supp = closed ball: zero outside; positive well inside (1 - F(t) underflows
        # to 0 in floating point only for t within ~1e-2 of 1, ERBS being flat there)
        assert np.all(d[v > 0] < RR), type(m).__name__
        assert np.all(v[d < 0.9 * RR] > 0), type(m).__name__
        assert np.all((v >= 0) & (v <= 1))
        # the box bound used for neighbour searches contains the ball
        box = m.coord_bound(np.array(RR))
        assert np.all(np.abs(y[v > 0]) <= box * (1 + 1e-12))


def test_l1_in_the_plane_is_linf_after_45_degree_rotation():
    """Eq. (41) with the rotation: |z|_1 = |(z1 + z2, z1 - z2)|_inf."""
    y = RNG.normal(size=(500, 2))
    u = np.stack([y[:, 0] + y[:, 1], y[:, 0] - y[:, 1]], -1)
    R = np.full(500, 0.8)
    np.testing.assert_allclose(L1(2).bump_jet(y, R, K)[0], LInf(2).bump_jet(u, R, K)[0], rtol=0, atol=1e-15)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_bump_derivatives_match_finite_differences(n):
    h = 1e-6
    for m in all_metrics(n):
        if m.max_nu == 0:
            with pytest.raises(InvalidParameterError):
                m.bump_jet(np.zeros((1, n)), np.ones(1), K, nu=1)
            continue
        RR = 0.4 if isinstance(m, Bounded) else 1.0
        # stay away from coordinate hyperplanes where l_p (p < 2) is only C^1
        y = (0.1 + 0.5 * RNG.random((50, n))) * RNG.choice([-1, 1], size=(50, n)) / np.sqrt(n)
        R = np.full(50, RR)
        nu = m.max_nu
        v, g, H = m.bump_jet(y, R, K, nu)
        for k in range(n):
            e = np.zeros(n)
            e[k] = h
            vp, gp, _ = m.bump_jet(y + e, R, K, nu)
            vm, gm, _ = m.bump_jet(y - e, R, K, nu)
            assert np.max(np.abs((vp - vm) / (2 * h) - g[:, k])) <= 1e-6 * max(1, np.abs(g).max()), type(m).__name__
            if nu >= 2:
                assert np.max(np.abs((gp - gm) / (2 * h) - H[:, :, k])) <= 1e-5 * max(1, np.abs(H).max())


def test_smoothness_limits_and_parameter_errors():
    assert Lp(2, 1.5).max_nu == 1 and Lp(2, 2.5).max_nu == 2 and QuasiNorm(2, 0.5).max_nu == 0
    with pytest.raises(InvalidParameterError, match="nu"):
        Lp(2, 1.5).bump_jet(np.ones((1, 2)), np.ones(1), K, nu=2)
    with pytest.raises(InvalidParameterError, match="p"):
        Lp(2, 0.5)
    with pytest.raises(InvalidParameterError, match="p"):
        QuasiNorm(2, 1.5)
    with pytest.raises(InvalidParameterError, match="weights"):
        Euclidean(2, [1.0, -1.0])
    with pytest.raises(InvalidParameterError, match="R"):
        Bounded(Euclidean(2)).bump_jet(np.ones((1, 2)), np.ones(1) * 1.5, K)
    with pytest.raises(InvalidParameterError, match="metric"):
        as_metric("nonsense", 2)
    assert isinstance(as_metric(1, 3), L1) and isinstance(as_metric(np.inf, 3), LInf)
    assert isinstance(as_metric(0.5, 2), QuasiNorm) and isinstance(as_metric(None, 2), Euclidean)


def test_quasi_norm_is_not_convex_but_star_shaped():
    """Case 1.0: the unit ball of sum |y_k|^p, p < 1, is an astroid-like star."""
    m = QuasiNorm(2, 0.5)
    a, b = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    assert m.norm(a) == 1 and m.norm(b) == 1
    assert m.norm(0.5 * (a + b)) > 1                 # midpoint outside: not convex
    t = np.linspace(0, 1, 11)[:, None]
    assert np.all(np.diff(m.norm(t * (a + b) * 0.3)) > 0)   # monotone along rays: star-shaped


@pytest.mark.parametrize("form,cls,p,w", [
    ("euclidean", Euclidean, None, 1.0), (("euclidean", [1.0, 2.0, 3.0]), Euclidean, None, [1.0, 2.0, 3.0]),
    ("l2", Euclidean, None, 1.0), ("linf", LInf, None, 1.0), (("linf", 2.0), LInf, None, 2.0),
    ("chebyshev", LInf, None, 1.0), ("l1", L1, None, 1.0), (("manhattan", [1, 1, 2]), L1, None, [1, 1, 2]),
    (("lp", 3), Lp, 3.0, 1.0), (("lp", 3, [2.0, 1.0, 1.0]), Lp, 3.0, [2.0, 1.0, 1.0]), (("LP", 2), Euclidean, None, 1.0),
    (("lp", 1), L1, None, 1.0), (("lp", np.inf), LInf, None, 1.0), (("quasi", 0.5), QuasiNorm, 0.5, 1.0),
    (("quasi", 0.5, 3.0), QuasiNorm, 0.5, 3.0), (3, Lp, 3.0, 1.0), (2.5, Lp, 2.5, 1.0),
])
def test_every_documented_metric_form(form, cls, p, w):
    """Each form the as_metric docstring lists gives the right metric (the issue found
    ("lp", 3) and ("bounded", ...) refused as unknown)."""
    m = as_metric(form, 3)
    assert type(m) is cls
    np.testing.assert_array_equal(m.w, np.broadcast_to(np.asarray(w, float), (3,)))
    if p is not None:
        assert m.p == p


def test_bounded_forms_and_refusals():
    for form, base in (("bounded", Euclidean), (("bounded",), Euclidean), (("bounded", "linf"), LInf),
                       (("bounded", ("lp", 3)), Lp), (("d/(1+d)", ("l1", 2.0)), L1),
                       (("bounded", Lp(3, 4.0)), Lp)):
        m = as_metric(form, 3)
        assert isinstance(m, Bounded) and type(m.base) is base, form
    y = RNG.random((50, 3)) - 0.5
    m = as_metric(("bounded", "linf"), 3)
    d = m.norm(y)
    v = m.bump_jet(y, np.full(50, 0.3), K)[0]
    assert np.all(v[d >= 0.3] == 0) and np.all(v[d < 0.27] > 0)       # the d/(1+d) ball
    for bad in (("lp",), ("lp", 3, 1.0, 2.0), ("foo", 1), ("bounded", "bounded"), ("quasi", 2.0),
                True, -1.0, ("bounded", "l1", "l2"), [], Euclidean(2)):
        with pytest.raises(InvalidParameterError, match="metric|p"):
            as_metric(bad, 3)
