"""Delaunay star covers in R^n, n >= 3 (gerbs_core.scattered.star_nd): the point sets they
refuse (each error naming the points), the settings they check, and the point location
(visibility walk with Qhull's find_simplex as the long-walk fallback).
"""
import itertools

import numpy as np
import pytest
from scipy.spatial import Delaunay

from gerbs_core import GERBSInterpolator
from gerbs_core.errors import InvalidParameterError, InvalidPointSetError
from gerbs_core.kernels import ERBS
from gerbs_core.scattered.star_nd import DelaunayStarCover


def _build(points, **kw):
    return GERBSInterpolator(points, np.zeros(len(points)), **kw)


def _flat_simplex_points(points):
    """Points of the simplices of scipy's Delaunay whose volume is ~0 (relative)."""
    S = Delaunay(points).simplices
    E = points[S[:, 1:]] - points[S[:, :1]]
    vol = np.abs(np.linalg.det(E))
    return set(np.unique(S[vol <= 1e-9 * np.abs(E).max() ** 3]).tolist())


def test_too_few_points_for_a_simplex():
    with pytest.raises(InvalidPointSetError, match="in R.3 needs >= 4 points, got 3"):
        _build(np.eye(3))


def test_points_in_a_hyperplane_are_refused_naming_all():
    p = np.random.default_rng(0).uniform(0.0, 1.0, (10, 3))
    p[:, 2] = 0.5
    with pytest.raises(InvalidPointSetError, match="in a hyperplane") as exc:
        _build(p)
    assert exc.value.indices == tuple(range(10))


def test_numerically_coincident_points_are_named():
    p = np.random.default_rng(1).uniform(0.0, 1.0, (20, 3))
    p[5] = p[4] * (1 + 1e-15)
    with pytest.raises(InvalidPointSetError, match="numerically coincident") as exc:
        _build(p)
    assert set(exc.value.indices) <= {4, 5} and len(exc.value.indices) == 1


@pytest.mark.parametrize("jitter", [0.0, 1e-13])
def test_flat_delaunay_simplices_of_a_grid_are_refused(jitter):
    """A cubic grid is co-spherical: Qhull's triangulated output has zero-volume simplices
    (exactly singular at jitter 0, nearly so with a tiny jitter); the error names their
    points."""
    g = np.array(list(itertools.product(range(3), repeat=3)), float)
    g += np.random.default_rng(2).normal(0.0, jitter, g.shape)
    with pytest.raises(InvalidPointSetError, match="flat.*simplices") as exc:
        _build(g)
    flat = _flat_simplex_points(g)
    assert flat and set(exc.value.indices) == flat


@pytest.mark.parametrize("kw, name", [(dict(shrink=0.0), "shrink"),
                                      (dict(shrink=1.2), "shrink"),
                                      (dict(kappa=1.5), "kappa"), (dict(kappa=0.0), "kappa")])
def test_bad_gauge_settings_name_the_argument(kw, name):
    p = np.random.default_rng(3).uniform(0.0, 1.0, (20, 3))
    with pytest.raises(InvalidParameterError) as exc:
        _build(p, **kw)
    assert exc.value.name == name


@pytest.fixture(scope="module")
def cover():
    p = np.random.default_rng(4).uniform(0.0, 1.0, (60, 3))
    return DelaunayStarCover(p, ERBS())      # no tree given: built on first use


@pytest.mark.parametrize("max_steps", [None, 1])
def test_locate_finds_the_simplex_qhull_finds(cover, max_steps):
    x = np.random.default_rng(5).uniform(-0.2, 1.2, (400, 3))
    t = cover.locate(x, max_steps=max_steps)
    ref = cover.tri.find_simplex(x, tol=1e-12)
    assert (ref < 0).any() and (ref >= 0).any()     # points inside and outside the hull
    np.testing.assert_array_equal(t < 0, ref < 0)
    inside = t >= 0
    # the simplex found contains the point (barycentric coordinates >= 0)
    T = cover.tri.transform[t[inside]]
    lam = np.einsum("mij,mj->mi", T[:, :3], x[inside] - T[:, 3])
    lam = np.concatenate([lam, 1 - lam.sum(1, keepdims=True)], axis=1)
    assert lam.min() >= -1e-9


def test_psi_jet_of_no_star_is_zero(cover):
    x = np.full((5, 3), 0.5)
    idx = np.full((5, 4), -1)
    v, g, h = cover.psi_jet(x, idx, 2)
    assert v.shape == (5, 4) and g.shape == (5, 4, 3) and h.shape == (5, 4, 3, 3)
    assert not v.any() and not g.any() and not h.any()
