"""Pickling and copy.deepcopy keep the package's values what they were: the same results,
and their read-only arrays read-only (found by a review: numpy restores arrays writeable,
and an unpickled curve's ``local_curves[...] = 7`` changed what it computed)."""
import copy
import pickle

import numpy as np
import pytest

import gerbs_core as g
from gerbs_core.datasets.primitives import icosphere

rng = np.random.default_rng(0)
P2 = rng.random((60, 2))


def _interpolator():
    I = g.GERBSInterpolator(P2, np.sin(P2).sum(1))
    return I, lambda o: o(np.array([[0.4, 0.6], [0.5, 0.5]]), nu=1), ["points"]


def _curve():
    c = g.GERBSCurve([0.0, 1.0, 2.0, 3.0], [[0.0, 0.0], [1.0, 1.0]])
    return c, lambda o: o(np.array([1.2, 1.5])), ["knots", "local_curves"]


def _derivative_curve():
    c = g.GERBSCurve([0.0, 1.0, 2.0, 3.0], [[0.0, 0.0], [1.0, 1.0]]).derivative(1)
    return c, lambda o: o(np.array([1.2, 1.5])), ["knots", "local_curves"]


def _basis():
    b = g.GERBSBasis([0.0, 1.0, 2.5, 3.0, 4.0])
    return b, lambda o: o(np.array([1.2, 2.7])), ["knots"]


def _surface():
    V, F = icosphere(1)
    S = g.BlendingSurface(V, F)
    return S, lambda o: o.tessellate(2)[0], ["coefficients"]


def _stencil():
    V, F = icosphere(1)
    st = g.BlendingSurface(V, F).stencil(2)
    return st, lambda o: o.apply(V * 1.5), ["triangles"]


MAKERS = [_interpolator, _curve, _derivative_curve, _basis, _surface, _stencil]


@pytest.mark.parametrize("make", MAKERS, ids=lambda m: m.__name__.strip("_"))
@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_a_copy_computes_the_same_and_stays_read_only(make, how):
    obj, evaluate, arrays = make()
    before = evaluate(obj)
    for name in arrays:
        assert not getattr(obj, name).flags.writeable
    dup = pickle.loads(pickle.dumps(obj)) if how == "pickle" else copy.deepcopy(obj)
    assert type(dup) is type(obj) and dup is not obj
    np.testing.assert_array_equal(evaluate(dup), before)
    for name in arrays:
        a = getattr(dup, name)
        assert not a.flags.writeable, name
        with pytest.raises(ValueError):
            a[...] = 7.0
    with pytest.raises(AttributeError, match="immutable"):
        dup.anything = 1
    np.testing.assert_array_equal(evaluate(dup), before)


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_the_errors_survive_pickling_with_their_attributes(how):
    """Found by a review: InvalidMeshError and InvalidParameterError could not be pickled
    or deep-copied (their arguments are not their message), so one raised in a worker
    process broke a ProcessPoolExecutor instead of reaching the caller."""
    from gerbs_core.errors import (InvalidMeshError, InvalidParameterError,
                                   InvalidPointSetError, ResourceLimitError)

    with pytest.raises(InvalidMeshError) as info:
        g.BlendingSurface([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [(0, 1, 2)])
    errors = [info.value, InvalidParameterError("alpha", "must be > 0"),
              InvalidPointSetError("points: duplicated", [3, 7]), ResourceLimitError("too big")]
    for err in errors:
        dup = pickle.loads(pickle.dumps(err)) if how == "pickle" else copy.deepcopy(err)
        assert type(dup) is type(err) and str(dup) == str(err) and dup.args == err.args
        assert vars(dup) == vars(err)
    assert errors[0].problem == "empty" and errors[1].name == "alpha"
    assert errors[2].indices == (3, 7)


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_the_surfaces_parts_stay_read_only_too(how):
    """Found by a review: MeshTopology, Lattice, RepairedMesh and the star gauges came back
    writable (an unpickled envelope's line_a, written, changed its gauge's values)."""
    V, F = icosphere(1)
    S = g.BlendingSurface(V, F)
    parts = {"topology": (S.topology, "face_vertices"), "lattice": (S.lattice(2), "face"),
             "repair": (S.repair, "vertex_map")}
    for name, (obj, attr) in parts.items():
        assert not getattr(obj, attr).flags.writeable, name
        dup = pickle.loads(pickle.dumps(obj)) if how == "pickle" else copy.deepcopy(obj)
        a = getattr(dup, attr)
        np.testing.assert_array_equal(a, getattr(obj, attr))
        with pytest.raises(ValueError):
            a[...] = 0
