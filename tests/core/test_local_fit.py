"""Local functions l_v: weighted least squares in chart coordinates, enlargement rule."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.charts import vertex_charts
from gerbs_core.errors import InvalidParameterError
from gerbs_core.face_shapes import face_shapes
from gerbs_core.local_fit import fit_local_functions, monomial_exponents, monomials
from gerbs_core.mesh_topology import MeshTopology


def _setup(V, F, mode="metric", degree=2, rest=None):
    topo = MeshTopology(F, len(V))
    sh = face_shapes(topo.face_offsets, topo.face_vertices, mode, V if rest is None else rest)
    ch = vertex_charts(topo.face_offsets, topo.face_vertices, sh.corners, sh.angles,
                       topo.star_offsets, topo.star_corners, topo.vertex_is_boundary, "keep")
    return topo, sh, ch, fit_local_functions(topo, ch, sh.corners, degree)


def _poly(d, rng):
    E = monomial_exponents(d)
    c = rng.normal(size=len(E))
    return lambda x, y: 0.4 + sum(ci * x ** a * y ** b for ci, (a, b) in zip(c, E))


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_flat_metric_fit_reproduces_polynomials(degree):
    V, F = P.delaunay_patch(60, 4)
    rng = np.random.default_rng(degree)
    p = _poly(degree, rng)
    topo, sh, ch, fits = _setup(V, F, degree=degree)
    Z = p(V[:, 0], V[:, 1])[:, None]
    C = fits.coefficients(Z)  # (V, M, 1)
    for v in range(len(V)):
        c = topo.star_corners[topo.star_offsets[v]]
        n = topo.corner_next[c]
        yn = ch.to_chart(c, sh.corners[n])[0]
        dn = V[topo.face_vertices[n], :2] - V[v, :2]
        rot = complex(*yn) / complex(*dn)  # chart = rotation of the plane about X_v
        assert abs(abs(rot) - 1) < 1e-12
        y = rng.uniform(-0.2, 0.2, size=(5, 2))
        xy = np.array([complex(*t) / rot for t in y])
        want = p(V[v, 0] + xy.real, V[v, 1] + xy.imag)
        got = Z[v, 0] + monomials(y, degree)[0] @ C[v, :, 0]
        assert np.abs(got - want).max() < 1e-10


@pytest.mark.parametrize("name,VF", [("tri", P.grid(5, 5, kind="tri")), ("ico", P.icosphere(1)),
                                     ("mixed", P.mixed_mesh(bend=0.4)), ("suzanne", P.suzanne())])
def test_enlargement_rule(name, VF):
    V, F = VF
    for mode in ("regular", "metric"):
        topo, sh, ch, fits = _setup(V, F, mode)
        small = (fits.n_data < 7) | (fits.cond > 100)
        # every fit has >= 7 data and condition <= 100 unless two extra layers were used
        assert np.all(fits.layers[small] == 2)
        # layers are only added when needed: a fit with one layer fewer would fail the rule
        assert np.all(fits.layers <= 2)
        assert np.all(np.isfinite(fits.cond))
    # triangle meshes of valence 6 have 6 < 7 one-ring data: enlargement is used
    if name in ("tri", "ico"):
        assert np.all(fits.layers >= 1)


def test_regular_mode_depends_only_on_topology_and_degree0():
    V, F = P.mixed_mesh()
    V2 = V + np.random.default_rng(0).normal(scale=0.1, size=V.shape)
    *_, a = _setup(V, F, "regular")
    *_, b = _setup(V2, F, "regular")
    assert np.array_equal(a.ids, b.ids) and np.array_equal(a.coef, b.coef)
    *_, z = _setup(V, F, "regular", degree=0)
    assert z.coef.shape[1] == 0 and np.all(z.coefficients(V).shape == (len(V), 0, 3))


def test_linear_in_positions():
    V, F = P.icosphere(1)
    *_, fits = _setup(V, F, "regular")
    rng = np.random.default_rng(1)
    A, B = rng.normal(size=V.shape), rng.normal(size=V.shape)
    lhs = fits.coefficients(2 * A - B)
    assert np.allclose(lhs, 2 * fits.coefficients(A) - fits.coefficients(B), atol=1e-12)


@pytest.mark.parametrize("bad", [-1, 4, 1.5, True])
def test_bad_degree(bad):
    V, F = P.icosphere(0)
    with pytest.raises(InvalidParameterError, match="degree"):
        _setup(V, F, degree=bad)
