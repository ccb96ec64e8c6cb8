"""BlendingSurface: partition of unity, cover, interpolation, reproduction, errors."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.errors import InvalidMeshError, InvalidParameterError, ResourceLimitError
from gerbs_core.mesh.surface import BlendingSurface
from gerbs_core.mesh.lattice import Lattice, output_counts

MESHES = {
    "tri_grid": P.grid(4, 4, kind="tri"),
    "quad_grid": P.grid(4, 4),
    "icosphere": P.icosphere(1),
    "uv_sphere": P.uv_sphere(8, 6),
    "mixed": P.mixed_mesh(),
    "mixed_bent": P.mixed_mesh(bend=0.5),
    "delaunay": P.delaunay_patch(30, 3),
}
_CACHE = {}


def surface(name, **kw):
    key = (name, tuple(sorted(kw.items())))
    if key not in _CACHE:
        V, F = MESHES[name]
        _CACHE[key] = BlendingSurface(V, F, **kw)
    return _CACHE[key]


def local_points(s, r=4):
    lat = Lattice(s.topology, r)
    return lat, lat.local_face, lat.map_to_polygon(s.layouts.corners, local=True)


@pytest.mark.parametrize("name", sorted(MESHES))
def test_partition_of_unity_and_cover(name):
    s = surface(name)
    lat, f, x = local_points(s)
    verts, Psi, psi = s.partition(f, x)
    assert np.abs(Psi.sum(1) - 1).max() <= 1e-14
    assert Psi.min() >= 0 and Psi.max() <= 1
    assert np.all(psi.max(1) > 0)          # every sample covered
    assert s.eps0 > 0
    print(f"eps0[{name}] = {s.eps0:.4f}")
    # Psi_v = 1 exactly at its own vertex (supports of the others stay away)
    at_v = np.isin(lat.local_sample, lat.vertex_sample)
    assert np.all(Psi[at_v].max(1) == 1.0)


@pytest.mark.parametrize("name", sorted(MESHES))
def test_interpolates_vertices_from_every_face(name):
    s = surface(name)
    V = MESHES[name][0]
    topo = s.topology
    S = s.evaluate(topo.corner_face, s.layouts.corners)  # every corner, from its own face
    assert np.abs(S - V[topo.face_vertices]).max() <= 1e-12
    pts, tris, nrm = s.tessellate(3)
    assert len(pts) == output_counts(topo, 3)[0]
    assert np.abs(pts[:len(V)] - V).max() <= 1e-12
    assert np.allclose(np.linalg.norm(nrm, axis=1), 1.0)


@pytest.mark.parametrize("name", ["icosphere", "mixed_bent", "uv_sphere", "delaunay"])
def test_derivatives_at_vertices_equal_local_function(name):
    s = surface(name)
    for v in range(0, s.topology.n_vertices, 3):
        ang = np.linspace(0, 2 * np.pi, 7, endpoint=False) + 0.1
        if s.charts.boundary[v]:
            ang = np.linspace(0.05, 0.95, 5) * s.charts.scale[v] * s.charts.span[v]
        y = 1e-3 * np.stack([np.cos(ang), np.sin(ang)], 1)
        A = s.chart_evaluate(v, y, 2)
        B = s.local_function(v, y, 2)
        for a, b in zip(A, B):
            assert np.abs(a - b).max() <= 1e-10 * max(1.0, np.abs(b).max())


def test_sphere_normals_point_outward():
    s = surface("icosphere")
    pts, _, nrm = s.tessellate(4)
    assert np.min(np.sum(pts * nrm, 1) / np.linalg.norm(pts, axis=1)) > 0.9


@pytest.mark.parametrize("degree", [1, 2])
def test_flat_rest_shape_reproduces_polynomial_graphs(degree):
    V, F = P.delaunay_patch(80, 5)
    flat = V.copy()
    p = {1: lambda x, y: 0.3 + 0.5 * x - 0.7 * y,
         2: lambda x, y: 0.3 + 0.5 * x - 0.7 * y + 1.1 * x * x - 0.8 * x * y + 0.6 * y * y}[degree]
    X = flat.copy()
    X[:, 2] = p(X[:, 0], X[:, 1])
    s = BlendingSurface(X, F, rest_positions=flat, boundary="keep")
    pts, _, _ = s.tessellate(5)
    assert np.abs(pts[:, 2] - p(pts[:, 0], pts[:, 1])).max() <= 1e-10


def test_graph_lengths_reproduction_error_is_third_order():
    p = lambda x, y: 0.3 + 0.5 * x - 0.7 * y + 1.1 * x * x - 0.8 * x * y + 0.6 * y * y  # noqa
    rows = []
    for n_side in (6, 11, 21):
        V, F = P.jittered_patch(n_side, 1)
        X = V.copy()
        X[:, 2] = p(X[:, 0], X[:, 1])
        s = BlendingSurface(X, F)  # bound to the graph's own 3D lengths
        pts, _, _ = s.tessellate(4)
        rows.append((1.0 / (n_side - 1), np.abs(pts[:, 2] - p(pts[:, 0], pts[:, 1])).max()))
    (h0, e0), (h1, e1) = rows[0], rows[-1]
    order = np.log(e0 / e1) / np.log(h0 / h1)
    print("h, max error:", rows, "order:", order)
    assert order >= 2.6 and all(b[1] < a[1] for a, b in zip(rows, rows[1:]))


def test_evaluate_derivatives_match_finite_differences():
    s = surface("mixed_bent")
    topo = s.topology
    f = np.arange(topo.n_faces)
    ctr = np.add.reduceat(s.layouts.corners, topo.face_offsets[:-1], 0) / topo.face_sizes[:, None]
    x = 0.6 * ctr + 0.4 * s.layouts.corners[topo.face_offsets[:-1] + 1]
    S, dS, HS = s.evaluate_all(f, x, 2)
    h = 1e-5
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        Sp, dp = s.evaluate_all(f, x + e, 1)
        Sm, dm = s.evaluate_all(f, x - e, 1)
        assert np.abs((Sp - Sm) / (2 * h) - dS[..., j]).max() < 1e-7
        assert np.abs((dp - dm) / (2 * h) - HS[..., j]).max() < 1e-5 * max(1.0, np.abs(HS).max())
    assert np.array_equal(s.evaluate(f, x, 1), dS)


def test_bad_input_and_caller_arrays_untouched():
    V, F = P.grid(3, 3)
    V0, F0 = V.copy(), F.copy()
    s = BlendingSurface(V, F)
    s.tessellate(2)
    s.stencil(2)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)
    # non-manifold edges and loose vertices are repaired with a warning (issue 14;
    # tests/core/test_mesh_repair.py), not refused
    s3 = BlendingSurface(np.random.default_rng(0).normal(size=(5, 3)),
                         [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    assert [w.tag for w in s3.warnings] == ["non_manifold_edge", "non_manifold_vertex"]
    s4 = BlendingSurface(np.vstack([V, [[9, 9, 9]]]), F)
    assert [(w.tag, w.indices) for w in s4.warnings] == [("unused_vertex", (len(V),))]
    bad = V.copy()
    bad[4] = np.nan
    with pytest.raises(InvalidMeshError) as e:
        BlendingSurface(bad, F)
    assert e.value.problem == "non_finite" and 4 in e.value.indices
    with pytest.raises(InvalidParameterError, match="kernel"):
        BlendingSurface(V, F, kernel="bogus")
    for name, kw in (("memory_budget", {"memory_budget": float("nan")}),
                     ("memory_budget", {"memory_budget": -1}),
                     ("eps0_resolution", {"eps0_resolution": 0}),
                     ("vertices", {})):
        with pytest.raises(InvalidParameterError, match=name):
            BlendingSurface("abc" if name == "vertices" else V, F, **kw)
    with pytest.raises(InvalidParameterError, match="boundary"):
        BlendingSurface(V, F, boundary="round")
    with pytest.raises(InvalidParameterError, match="nu"):
        s.evaluate(0, [0.1, 0.1], nu=3)
    with pytest.raises(InvalidParameterError, match="rest_positions"):
        BlendingSurface(V, F, rest_positions=V[:3])
    small = BlendingSurface(V, F, memory_budget=1e6)
    with pytest.raises(ResourceLimitError, match="estimated memory"):
        small.tessellate(200)
    with pytest.raises(ResourceLimitError, match="MB"):
        small.stencil(200)


def test_vertex_normals_as_hermite_data():
    V, F = P.icosphere(1)
    n = V / np.linalg.norm(V, axis=1, keepdims=True)  # exact sphere normals
    tilt = n + 0.3 * np.roll(n, 1, axis=1)             # deliberately different normals
    for normals in (n, tilt):
        s = BlendingSurface(V, F, normals=normals)
        nn = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        for v in range(0, len(V), 5):
            y = 1e-4 * np.array([[1.0, 0.3], [-0.2, 1.0]])
            J = s.chart_evaluate(v, y, 1)[1]            # dS/dy near v: tangent to n_v
            assert np.abs(np.einsum("pcj,c->pj", J, nn[v])).max() <= 1e-3 * np.abs(J).max()
        pts, _, _ = s.tessellate(3)
        assert np.abs(pts[:len(V)] - V).max() <= 1e-12
    with pytest.raises(InvalidParameterError, match="normals"):
        s.stencil(2)
    with pytest.raises(InvalidParameterError, match="normals"):
        BlendingSurface(V, F, normals=np.full_like(V, np.inf))


def test_normals_are_checked_only_where_the_repair_keeps_vertices():
    """A vertex the repair leaves out (unused) may carry a zero or NaN normal (Blender gives
    a vertex of only degenerate faces a zero one): the surface builds, bit for bit as
    without that vertex; a bad normal at a kept vertex is refused, naming its index."""
    V, F = P.icosphere(1)
    n = V / np.linalg.norm(V, axis=1, keepdims=True)
    Vx = np.vstack([V, [[5.0, 5.0, 5.0]]])              # an unused vertex
    for bad in ([0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]):
        s = BlendingSurface(Vx, F, normals=np.vstack([n, [bad]]))
        ref = BlendingSurface(V, F, normals=n)
        assert np.array_equal(s.tessellate(2)[0], ref.tessellate(2)[0])
    worse = n.copy()
    worse[7] = np.nan
    with pytest.raises(InvalidParameterError, match=r"normals: must be finite.*\[7\]"):
        BlendingSurface(V, F, normals=worse)


def test_a_zero_normal_leaves_that_vertex_free_with_a_warning():
    """A kept vertex with a zero normal (from a script's data) gets no Hermite normal: its local function is the one without normals, every other
    vertex's the one with them, and a zero_normal warning names it (input index)."""
    V, F = P.icosphere(1)
    n = V / np.linalg.norm(V, axis=1, keepdims=True) + 0.3 * np.roll(V, 1, axis=1)
    given = n.copy()
    given[7] = 0.0
    s = BlendingSurface(V, F, normals=given)
    free, tied = BlendingSurface(V, F), BlendingSurface(V, F, normals=n)
    assert np.array_equal(s.coefficients[7], free.coefficients[7])
    others = np.arange(len(V)) != 7
    assert np.array_equal(s.coefficients[others], tied.coefficients[others])
    assert not np.array_equal(s.coefficients[7], tied.coefficients[7])
    (w,) = [w for w in s.warnings if w.tag == "zero_normal"]
    assert w.indices == (7,) and w.element == "vertex" and "[7]" in w.message
    assert s.with_positions(V * 1.1).warnings == s.warnings
    assert not [w for w in tied.warnings if w.tag == "zero_normal"]
    # the repair's vertex numbers are the input's: an unused vertex 0 shifts them
    Vx = np.vstack([[[5.0, 5.0, 5.0]], V])
    sx = BlendingSurface(Vx, [tuple(int(i) + 1 for i in f) for f in F],
                         normals=np.vstack([[1.0, 0.0, 0.0], given]))
    assert [w.indices for w in sx.warnings if w.tag == "zero_normal"] == [(8,)]


@pytest.mark.parametrize("name", ["mixed_bent", "delaunay", "tri_grid"])
def test_straighten_rule(name):
    V, F = MESHES[name]
    s = BlendingSurface(V, F, boundary="straighten")
    lat, f, x = local_points(s, 3)
    verts, Psi, psi = s.partition(f, x)
    assert np.abs(Psi.sum(1) - 1).max() <= 1e-14 and s.eps0 > 0
    pts, _, _ = s.tessellate(3)
    assert np.abs(pts[:len(V)] - V).max() <= 1e-12
    assert np.abs(s.stencil(3).apply(V) - pts).max() <= 1e-12
    b = np.flatnonzero(s.topology.vertex_is_boundary)
    assert np.allclose(s.charts.scale[b] * s.charts.span[b], np.pi)
