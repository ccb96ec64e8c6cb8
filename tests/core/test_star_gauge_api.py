"""The public StarGauge / RadialEnvelope API beyond g and psi: the support radius rho~(y),
the certified ratio, the measured curvature of the support boundary, the input checks
(each naming its argument) and the reprs.
"""
import numpy as np
import pytest

from gerbs_core import RadialEnvelope, StarGauge
from gerbs_core.errors import InvalidParameterError, InvalidPointSetError

KAPPA, SHRINK = 0.8, 0.95
# a convex pentagon about c, star-shaped w.r.t. it
C = np.array([0.3, -0.2])
RING = C + np.array([[1.0, 0.0], [0.4, 1.1], [-0.9, 0.7], [-0.8, -0.6], [0.3, -1.0]])


def _ray_exit(ring, c, phi):
    """Distance from c along angle phi to the polygon boundary (independent of the
    envelope code: ray / segment intersection)."""
    d = np.array([np.cos(phi), np.sin(phi)])
    best = np.inf
    for a, b in zip(ring, np.roll(ring, -1, axis=0)):
        e = b - a
        M = np.array([d, -e]).T
        t, s = np.linalg.solve(M, a - c)
        if t > 0 and -1e-12 <= s <= 1 + 1e-12:
            best = min(best, t)
    return best


@pytest.fixture(scope="module")
def gauge():
    return StarGauge.from_polygon(C, RING, kappa=KAPPA, shrink=SHRINK)


def test_rho_lies_between_the_certified_bounds_of_the_polygon_radius(gauge):
    phi = np.linspace(-np.pi, np.pi, 361)[:-1]
    y = C + 0.37 * np.stack([np.cos(phi), np.sin(phi)], -1)
    rho = gauge.rho(y)
    exact = np.array([_ray_exit(RING, C, p) for p in phi])
    ratio = rho / exact
    assert ratio.max() <= SHRINK * (1 + 1e-12)
    assert ratio.min() >= gauge.min_ratio * (1 - 1e-12)
    assert gauge.min_ratio == gauge.envelope.min_ratio >= KAPPA * SHRINK * (1 - 1e-12)
    # rho~ depends on the ray only, and g = |y - c| / rho~ on it
    np.testing.assert_allclose(gauge.rho(C + 2.5 * (y - C)), rho, rtol=1e-13)
    np.testing.assert_allclose(gauge.g(y), 0.37 / rho, rtol=1e-12)


def test_rho_is_zero_outside_an_open_sector():
    ring = np.array([[1.0, 0.0], [0.7, 0.7], [0.0, 1.0]])     # a quarter: open chain
    g = StarGauge.from_polygon([0.0, 0.0], ring, closed=False)
    inside = g.rho([[0.5, 0.5], [0.6, 0.1]])
    assert np.all(inside > 0)
    assert np.all(g.rho([[-0.5, -0.5], [0.1, -0.6]]) == 0.0)


def test_max_curvature_matches_the_curvature_of_the_sampled_support_boundary(gauge):
    """max |kappa| * rho~ of the curve phi -> c + rho~(phi) e(phi), from finite differences
    of sampled boundary points (independent of curvature_stats' closed form)."""
    phi = np.linspace(-np.pi, np.pi, 40001)[:-1]
    e = np.stack([np.cos(phi), np.sin(phi)], -1)
    rho = gauge.rho(C + e)
    p = rho[:, None] * e
    d1 = (np.roll(p, -1, 0) - np.roll(p, 1, 0)) / 2
    d2 = np.roll(p, -1, 0) - 2 * p + np.roll(p, 1, 0)
    k = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.hypot(*d1.T) ** 3
    measured = float(np.max(k * rho))
    assert gauge.max_curvature == pytest.approx(measured, rel=2e-2)
    assert gauge.max_curvature == gauge.curvature_stats()["geometric"]
    assert gauge.envelope.max_curvature == pytest.approx(gauge.max_curvature, rel=1e-12)


def test_constructor_errors_name_the_argument(gauge):
    env = gauge.envelope
    for kw, name in [(dict(envelope=object()), "envelope"),
                     (dict(envelope=env, scale=float("nan")), "scale"),
                     (dict(envelope=env, scale=-1.0), "scale"),
                     (dict(envelope=env, center=[0.0, 1.0, 2.0]), "center"),
                     (dict(envelope=env, center=[0.0, np.inf]), "center")]:
        with pytest.raises(InvalidParameterError) as exc:
            StarGauge(**kw)
        assert exc.value.name == name
    with pytest.raises(InvalidParameterError) as exc:
        StarGauge.from_polygon([np.nan, 0.0], RING)
    assert exc.value.name == "center"


def test_evaluation_errors_name_the_argument(gauge):
    with pytest.raises(InvalidParameterError, match="y: expected shape"):
        gauge.g(np.zeros((4, 3)))
    for f in (gauge.g_derivs, gauge.psi_derivs):
        with pytest.raises(InvalidParameterError, match="nmax"):
            f(np.zeros((1, 2)), nmax=3)
    with pytest.raises(InvalidParameterError, match="nmax"):
        gauge.envelope.derivs([0.0], nmax=4)
    with pytest.raises(InvalidParameterError, match="nu"):
        gauge.envelope([0.0], nu=4)


def test_reprs_describe_the_star(gauge):
    text = repr(gauge)
    assert text.startswith("StarGauge(RadialEnvelope(closed, pieces=5,")
    assert "scale=1," in text
    open_env = RadialEnvelope([0.0, 1.0, 2.0], [1.0, 1.0, 1.0], closed=False)
    assert repr(open_env).startswith("RadialEnvelope(open, pieces=2,")


# ------------------------------------------------------------- RadialEnvelope inputs

def test_ring_repeating_its_first_vertex_is_the_same_star(gauge):
    again = RadialEnvelope.from_ring(np.vstack([RING, RING[:1]]) - C, kappa=KAPPA,
                                     shrink=SHRINK)
    t = np.linspace(0.0, 6.0, 101)
    np.testing.assert_array_equal(again.u_derivs(t), gauge.envelope.u_derivs(t))


def test_bad_rings_and_radii_are_refused():
    with pytest.raises(InvalidParameterError, match="ring: expected shape"):
        RadialEnvelope.from_ring(np.zeros((4, 3)))
    with pytest.raises(InvalidPointSetError, match="coincide with the centre") as exc:
        RadialEnvelope.from_ring([[1.0, 0.0], [0.0, 0.0], [-1.0, 1.0], [0.0, -1.0]])
    assert exc.value.indices == (1,)
    with pytest.raises(InvalidPointSetError, match="open ring spans >= 2.pi"):
        phi = np.linspace(0.0, 2 * np.pi + 0.5, 9)
        RadialEnvelope.from_ring(np.stack([np.cos(phi), np.sin(phi)], -1), closed=False)
    with pytest.raises(InvalidParameterError, match="radius: shape"):
        RadialEnvelope([0.0, 1.0, 2.0], [1.0, 1.0])
