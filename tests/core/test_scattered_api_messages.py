"""Errors name what the caller passed, and the objects print as what they are.

Found by a review: with a CustomCDF without derivatives ``interp(x, nu=1)`` named
``nmax`` and "this kernel's max_order = 0"; ``interp.basis(x, nu=7)`` was accepted while
``interp(x, nu=3)`` was refused, and ``basis(x, nu=1.5)`` named ``nmax``;
``curve.derivative(8)(t, 1)`` blamed "this kernel's max_order = 0" (ERBS has 8);
``GERBSBasis.rising(t, nmax=9)`` named ``nu``; a budget of 1e4 bytes read "estimated
memory 0 MB exceeds the budget 0 MB"; ``Stencil.apply`` of a (42, 3, 2) array said "42
rows, got 42"; reprs were ``<... object at 0x...>`` and CustomCDF's hid its smoothness.
"""
import math
import re

import numpy as np
import pytest

from gerbs_core import (ERBS, BlendingSurface, CustomCDF, GERBSBasis, GERBSCurve,
                        GERBSInterpolator)
from gerbs_core.datasets.primitives import icosphere
from gerbs_core.errors import InvalidParameterError, ResourceLimitError

RNG = np.random.default_rng(0)
P = RNG.random((40, 2))


def smooth(x):
    return x * x * (3.0 - 2.0 * x)


def smooth_d1(x):
    return 6.0 * x * (1.0 - x)


def test_kernel_without_derivatives_limits_nu_by_name():
    I = GERBSInterpolator(P, P.sum(1), kernel=CustomCDF(smooth), degree=1)
    assert I.max_order == 0
    for call in (lambda: I(P[:2], nu=1), lambda: I.basis(P[:2], nu=1),
                 lambda: I.memory_estimate(2, nu=1)):
        with pytest.raises(InvalidParameterError, match=r"derivative order 1 exceeds the "
                           r"interpolator's max_order = 0 \(its kernel, CustomCDF, has "
                           r"max_order = 0\)") as exc:
            call()
        assert exc.value.name == "nu"
    I1 = GERBSInterpolator(P, P.sum(1), kernel=CustomCDF(smooth, [smooth_d1], smoothness=1),
                           degree=1)
    assert I1.max_order == 1 and I1(P[:2], nu=1).shape == (2, 2)
    with pytest.raises(InvalidParameterError, match="max_order = 1") as exc:
        I1(P[:2], nu=2)
    assert exc.value.name == "nu"


@pytest.mark.parametrize("nu, match", [(3, "exceeds the interpolator's max_order = 2"),
                                       (7, "exceeds the interpolator's max_order = 2"),
                                       (1.5, "must be an integer, got 1.5"),
                                       (-1, "must be >= 0")])
def test_basis_checks_nu_as_the_call_does(nu, match):
    I = GERBSInterpolator(P, P.sum(1), degree=1)
    for call in (lambda: I(P[:1], nu=nu), lambda: I.basis(P[:1], nu=nu)):
        with pytest.raises(InvalidParameterError, match=re.escape(match)) as exc:
            call()
        assert exc.value.name == "nu"
    assert [a.shape for a in I.basis(P[:1], nu=2)[1:]] == [(1, 3), (1, 3, 2), (1, 3, 2, 2)]


def test_memory_messages_use_a_readable_unit():
    I = GERBSInterpolator(P, P.sum(1), degree=1, memory_budget=1e4)
    with pytest.raises(ResourceLimitError, match=r"estimated memory [\d.]+ kB exceeds the "
                       r"budget 10 kB \(memory_budget\)"):
        I(RNG.random((1000, 2)))


def test_curve_derivative_says_its_orders_are_used_up():
    c = GERBSCurve([0.0, 1.0, 2.0, 3.0], [[0.0], [1.0]])
    assert c.max_order == 8 and c.derivative(3).max_order == 5
    with pytest.raises(InvalidParameterError, match=r"derivative order 1 exceeds this "
                       r"curve's max_order = 0 \(it is derivative\(8\) of a curve of "
                       r"max_order 8") as exc:
        c.derivative(8)(0.5, 1)
    assert exc.value.name == "nu"
    with pytest.raises(InvalidParameterError, match="this curve's max_order = 8$"):
        c.derivative(9)


def test_basis_names_nmax_and_nu_as_passed():
    b = GERBSBasis([0.0, 1.0, 2.0, 3.0])
    with pytest.raises(InvalidParameterError, match="this basis's max_order = 8") as exc:
        b.rising(0.5, 9)
    assert exc.value.name == "nmax"
    with pytest.raises(InvalidParameterError) as exc:
        b.active(0.5, 9)
    assert exc.value.name == "nmax"
    with pytest.raises(InvalidParameterError, match="this basis's max_order = 8") as exc:
        b(0.5, 9)
    assert exc.value.name == "nu"


def test_stencil_apply_names_the_extra_axes():
    st = BlendingSurface(*icosphere(1)).stencil(2)
    with pytest.raises(InvalidParameterError, match=re.escape(
            "X: must be a (42,) or (42, k) array of vertex positions, got 3 axes "
            "(shape (42, 3, 2))")):
        st.apply(np.zeros((42, 3, 2)))


def test_reprs_are_short_and_informative():
    k = CustomCDF(smooth, [smooth_d1], smoothness=1)
    assert repr(k).endswith(", smoothness=1)") and repr(k).startswith("CustomCDF(<function smooth")
    assert repr(CustomCDF(smooth)).endswith("(), smoothness=-1)")
    assert repr(CustomCDF(smooth, smoothness=math.inf)).endswith("smoothness=inf)")
    e = repr(ERBS())
    assert repr(GERBSBasis([0, 1, 2, 3])) == f"GERBSBasis(n=2, knots=[0 .. 3], kernel={e})"
    c = GERBSCurve([0, 1, 2, 3], [[0.0, 0.0], [1.0, 1.0]])
    assert repr(c) == f"GERBSCurve(n=2, d=2, m=0, knots=[0 .. 3], kernel={e})"
    assert repr(c.derivative(2)).endswith(", derivative=2)")
    mixed = GERBSBasis([0, 1, 2, 3], ["erbs", "affine", "erbs"])
    assert repr(mixed).endswith("kernel=<3 per interval: Affine, ERBS>)")
    I = GERBSInterpolator(P, np.c_[P, P], degree=1)
    assert repr(I) == (f"GERBSInterpolator(N=40, n=2, values=(4,), cover='delaunay', "
                       f"basis='minimal', degree=1, kernel={e})")
    Ib = GERBSInterpolator(P, P.sum(1), cover="balls", metric=("lp", 3), degree=1)
    assert repr(Ib).startswith("GERBSInterpolator(N=40, n=2, values=(), cover='balls', "
                               "metric=Lp(n=2, p=3), basis='general'")
    assert str(I) == repr(I)


def test_the_mesh_objects_have_reprs_too():
    """(Were ``<... object at 0x...>``.)"""
    from gerbs_core import BlendingSurface
    from gerbs_core.datasets.primitives import icosphere

    V, F = icosphere(1)
    S = BlendingSurface(V, F)
    assert repr(S) == (f"BlendingSurface(vertices=42, faces=80, kernel={ERBS()!r}, "
                       f"boundary='keep')")
    st = S.stencil(2)
    assert repr(st).startswith("Stencil(points=162, vertices=42, resolution=2, nnz_per_row=")
    assert repr(S.lattice(2)) == "Lattice(resolution=2, n_points=162, n_triangles=320, faces=80)"
