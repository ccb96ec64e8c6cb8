"""Stencils: the output as a fixed linear map of the positions; locality; partial updates.

Locality implied by the construction (gerbs_core.mesh.stencil): a sample of face f
depends on the positions of f's corners u and on those the coefficients of u depend
on (the operator's row block of u). So moving vertex w changes exactly the samples of
the faces having a corner u with u == w or a non-zero in column w of u's rows.
"""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.mesh.agreement import MMAX
from gerbs_core.mesh.lattice import Lattice
from gerbs_core.mesh.surface import BlendingSurface

MESHES = {
    "tri_grid": lambda: P.grid(4, 4, kind="tri"),
    "quad_grid": lambda: P.grid(4, 4),
    "icosphere": lambda: P.icosphere(1),
    "uv_sphere": lambda: P.uv_sphere(8, 6),
    "mixed_bent": lambda: P.mixed_mesh(bend=0.5),
    "delaunay": lambda: P.delaunay_patch(30, 3),
}


@pytest.mark.parametrize("name", sorted(MESHES))
def test_stencil_equals_direct_evaluation(name):
    V, F = MESHES[name]()
    s = BlendingSurface(V, F)
    st = s.stencil(4)
    pts, tris, _ = s.tessellate(4)
    W = st.matrix()
    assert W.shape == st.shape == (len(pts), len(V))
    assert np.abs(st.apply(V) - pts).max() <= 1e-12
    assert np.abs(W @ V - pts).max() <= 1e-12
    assert np.array_equal(st.triangles, tris)
    assert np.array_equal(st.vertex_samples, np.arange(len(V)))
    # rows are affine combinations (constants are reproduced)
    assert np.abs(np.asarray(W.sum(axis=1)).ravel() - 1).max() <= 1e-12
    # new positions: the stencil (bound to the rest shape) == direct evaluation
    Y = V + np.random.default_rng(1).normal(scale=0.05, size=V.shape)
    assert np.abs(st.apply(Y) - s.with_positions(Y).tessellate(4)[0]).max() <= 1e-12


def test_stencil_depends_on_the_rest_shape_not_on_the_positions():
    V, F = P.mixed_mesh(bend=0.3)
    Y = V + np.random.default_rng(2).normal(scale=0.1, size=V.shape)
    s = BlendingSurface(V, F)
    A = s.stencil(3).matrix()
    assert (A != s.with_positions(Y).stencil(3).matrix()).nnz == 0
    assert (A != BlendingSurface(Y, F, rest_positions=V).stencil(3).matrix()).nnz == 0
    assert (A != BlendingSurface(Y, F).stencil(3).matrix()).nnz > 0  # another rest shape


def _affected_faces(s, w):
    op, topo = s.model.operator.tocsc(), s.topology
    rows = op.indices[op.indptr[w]:op.indptr[w + 1]]
    us = np.union1d(np.unique(rows // MMAX), [w])
    return np.unique(topo.corner_face[np.isin(topo.face_vertices, us)])


@pytest.mark.parametrize("name", ["icosphere", "mixed_bent", "quad_grid", "delaunay"])
def test_locality_exact(name):
    V, F = MESHES[name]()
    s = BlendingSurface(V, F)
    r = 3
    st = s.stencil(r)
    lat = Lattice(s.topology, r)
    Wc = st.matrix().tocsc()
    topo = s.topology
    base = s.tessellate(r)[0]
    for w in range(0, topo.n_vertices, 2):
        rows = Wc.indices[Wc.indptr[w]:Wc.indptr[w + 1]]
        allowed = np.isin(lat.face, _affected_faces(s, w))
        assert allowed[rows].all()
        # moving w changes exactly within the allowed samples
        Y = V.copy()
        Y[w] += [0.03, -0.02, 0.05]
        d = np.abs(s.with_positions(Y).tessellate(r)[0] - base).max(axis=1)
        assert np.all(d[~allowed] == 0.0) and d[allowed].max() > 0
        # the partial update gives the same points
        pts = base.copy()
        st.apply_moved(pts, np.array([w]), (Y - V)[[w]])
        assert np.abs(pts - s.with_positions(Y).tessellate(r)[0]).max() <= 1e-12


@pytest.mark.parametrize("name", ["icosphere", "mixed_bent", "grid30", "tri30"])
def test_partial_updates_take_single_columns_of_the_coefficient_map(name, monkeypatch):
    # apply_moved needs only the moved vertices' columns (CoupledFits.columns), so it
    # never makes the whole operator; the columns equal the operator's to round-off.
    # On the 30 x 30 grids they are computed on a neighbourhood (coupling_local), which
    # is checked to be a small part of the mesh; with one hop less it would be wrong.
    from gerbs_core.mesh import coupling
    from gerbs_core.mesh.coupling_local import neighbourhood
    V, F = (P.grid(30, 30, kind="tri" if name == "tri30" else "quad") if name.endswith("30")
            else MESHES[name]())
    st = BlendingSurface(V, F).stencil(3)
    if name.endswith("30"):
        assert len(neighbourhood(st.fits._graph, [1, 4], coupling.LOCAL_REACH)) < len(V) // 2
    pts = st.apply(V)
    moved = np.array([1, 4])
    delta = np.array([[0.02, 0.0, -0.01], [0.0, 0.03, 0.01]])
    st.apply_moved(pts, moved, delta)
    assert not st.fits.operator_built
    Y = V.copy()
    Y[moved] += delta
    assert np.abs(pts - st.apply(Y)).max() <= 1e-13
    cols = st.fits.columns(moved).toarray()
    op = st.operator[:, moved].toarray()
    assert np.abs(cols - op).max() <= 1e-10 * max(np.abs(op).max(), 1.0)
    assert np.array_equal(cols != 0, op != 0) or np.abs(cols[op == 0]).max() <= 1e-12
    if name.endswith("30"):  # the control: a neighbourhood two hops short misses entries
        monkeypatch.setattr(coupling, "LOCAL_REACH", coupling.LOCAL_REACH - 2)
        st.fits._last = None
        st.fits.__dict__.pop("operator")
        short = st.fits.columns(moved).toarray()
        assert np.abs(short - op).max() > 1e-6 * np.abs(op).max()  # 1e-10 when right


def test_support_is_a_few_rings():
    # a coefficient depends on the data rings (2) plus one ring per coupling sweep (2);
    # a sample on the corners of its face: moving w reaches the faces within 5 rings
    V, F = P.icosphere(2)
    s = BlendingSurface(V, F)
    topo = s.topology
    for w in (0, 17, 100):
        ring = topo.k_ring(w, 5, include_self=True)
        fv_ok = np.zeros(topo.n_faces, dtype=bool)
        np.logical_or.at(fv_ok, topo.corner_face, np.isin(topo.face_vertices, ring))
        affected = _affected_faces(s, w)
        assert fv_ok[affected].all() and len(affected) < 0.6 * topo.n_faces


def _hashed_edges(L):
    """The undirected edges of the lattice triangles by brute force: sorted keys, and the
    key of the edge from corner i to corner i+1 of every triangle."""
    T = np.asarray(L.triangles, dtype=np.int64)
    a, b = T, np.roll(T, -1, axis=1)
    key = np.minimum(a, b) * L.n_points + np.maximum(a, b)
    return np.unique(key), key


def _edge_keys(L, ev):
    ev = np.asarray(ev, dtype=np.int64)
    return np.minimum(ev[:, 0], ev[:, 1]) * L.n_points + np.maximum(ev[:, 0], ev[:, 1])


@pytest.mark.parametrize("name", ["suzanne", "mixed", "uv_sphere", "delaunay", "tri_grid"])
@pytest.mark.parametrize("r", [1, 2, 5])
def test_lattice_edges_equal_hashed_edges(name, r):
    V, F = {"suzanne": P.suzanne, "mixed": P.mixed_mesh, "uv_sphere": lambda: P.uv_sphere(8, 6),
            "delaunay": lambda: P.delaunay_patch(30, 3),
            "tri_grid": lambda: P.grid(4, 4, kind="tri")}[name]()
    L = Lattice(BlendingSurface(V, F).topology, r)
    res = L.edges()
    if res is None:  # only quads at resolution 1 (a diagonal may be shared)
        assert r == 1 and np.any(L.topology.face_sizes == 4)
        return
    ev, ce = res
    want, corner_keys = _hashed_edges(L)
    got = _edge_keys(L, ev)
    assert len(np.unique(got)) == len(got)  # no edge twice
    assert np.array_equal(np.sort(got), want)  # every triangle edge, nothing else
    assert np.array_equal(got[ce], corner_keys)  # corner i -> i+1 of every triangle


def test_lattice_edges_merge_the_repeats_at_an_interior_valence_2_vertex():
    # vertex 1 is interior with valence 2: both quads have it at corner 1, whose lattice
    # diagonal joins the same two edge samples in both faces
    from gerbs_core.mesh.topology import MeshTopology
    L = Lattice(MeshTopology([[0, 1, 2, 3], [2, 1, 0, 4]], 5), 3)
    ev, ce = L.edges()
    want, corner_keys = _hashed_edges(L)
    got = _edge_keys(L, ev)
    # 3 segments per mesh edge + per quad at r = 3: 2 x 6 inner grid edges + 9 diagonals
    naive = L.topology.n_edges * 3 + 2 * (12 + 9)
    assert len(got) == len(want) == naive - 1  # the repeat was merged, nothing else
    assert np.array_equal(np.sort(got), want) and np.array_equal(got[ce], corner_keys)


def test_stencil_factors_are_canonical_csr_and_small():
    V, F = P.suzanne()
    st = BlendingSurface(V, F).stencil(4)
    for M in (st.base, st.mono, st.operator):
        assert M.has_canonical_format
    # on a mesh larger than a few rings, the evaluation factors B + E hold fewer entries
    # than the explicit product W (whose rows reach every vertex of the corners' supports)
    W = st.matrix()
    print("entries per row: B + E", (st.base.nnz + st.mono.nnz) / W.shape[0], "W", W.nnz / W.shape[0])
    assert st.base.nnz + st.mono.nnz < W.nnz


def _refusal(fn, cls):
    with pytest.raises(cls) as info:
        fn()
    return info.value


def test_non_finite_positions_are_refused_alike_everywhere():
    """The constructor, with_positions and the stencil's apply refuse NaN / infinite
    positions with one error: InvalidMeshError ``non_finite`` naming the argument and
    the input rows, each said once (they used to be accepted silently by the last two:
    NaN points out)."""
    from gerbs_core.errors import InvalidMeshError

    V, F = P.icosphere(1)
    s = BlendingSurface(V, F)
    st = s.stencil(2)
    bad = V.copy()
    bad[3, 1], bad[7, 2] = np.nan, -np.inf
    for fn, name in ((lambda: BlendingSurface(bad, F), "vertices"),
                     (lambda: BlendingSurface(V, F, rest_positions=bad), "rest_positions"),
                     (lambda: s.with_positions(bad), "vertices"),
                     (lambda: st.apply(bad), "X")):
        err = _refusal(fn, InvalidMeshError)
        assert (err.problem, err.element, err.name) == ("non_finite", "vertex", name)
        assert err.indices == (3, 7)
        assert str(err) == f"{name}: NaN or infinite coordinates at indices [3, 7]"
    err = _refusal(lambda: st.apply(bad[:, 1]), InvalidMeshError)   # one column (V,)
    assert err.indices == (3,) and str(err) == "X: NaN or infinite coordinates at indices [3]"
    assert np.abs(st.apply(V) - s.tessellate(2)[0]).max() <= 1e-12   # finite input: as before


def test_apply_with_the_wrong_vertex_count_names_x_and_both_counts():
    from gerbs_core.errors import InvalidParameterError

    V, F = P.icosphere(1)
    st = BlendingSurface(V, F).stencil(2)
    for X, got in ((V[:-1], 41), (np.vstack([V, V[:1]]), 43), (V[:, 0][:-2], 40)):
        err = _refusal(lambda: st.apply(X), InvalidParameterError)
        assert err.name == "X"
        assert f"{len(V)} rows, got {got}" in str(err)
    err = _refusal(lambda: st.apply(3.0), InvalidParameterError)
    assert err.name == "X" and "42 rows, got 0" in str(err)
    err = _refusal(lambda: st.apply("abc"), InvalidParameterError)
    assert err.name == "X" and "real (42, k) array" in str(err)


def test_a_bad_drag_step_is_refused_and_leaves_the_points_untouched():
    """Stencil.apply_moved (the drag path) refuses NaN / infinite deltas, a delta with
    another row count than ``moved``, and moved indices outside the mesh or repeated,
    before writing: the points stay bit-identical (they used to become NaN, or scipy's
    shape error came after nothing / the repeated vertex counted twice)."""
    from gerbs_core.errors import InvalidMeshError, InvalidParameterError

    V, F = P.icosphere(1)
    st = BlendingSurface(V, F).stencil(2)
    pts = st.apply(V)
    keep = pts.copy()
    nan_delta = np.array([[0.0, np.nan, 0.0], [0.1, 0.0, 0.0]])
    err = _refusal(lambda: st.apply_moved(pts, np.array([2, 5]), nan_delta), InvalidMeshError)
    assert (err.problem, err.name, err.indices) == ("non_finite", "delta", (0,))
    for moved, delta, name, text in (
            (np.array([2, 5]), np.zeros((3, 3)), "delta", "2 rows, got shape (3, 3)"),
            (np.array([2, 42]), np.zeros((2, 3)), "moved", "[0, 42)"),
            (np.array([-1]), np.zeros((1, 3)), "moved", "[0, 42)"),
            (np.array([2.0]), np.zeros((1, 3)), "moved", "vertex indices"),
            (np.array([2, 2]), np.zeros((2, 3)), "moved", "repeat")):
        err = _refusal(lambda: st.apply_moved(pts, moved, delta), InvalidParameterError)
        assert err.name == name and text in str(err), str(err)
    assert np.array_equal(pts, keep)
    # a valid step still works and equals the full product
    Y = V.copy()
    Y[[2, 5]] += [[0.0, 0.02, 0.0], [0.01, 0.0, -0.01]]
    st.apply_moved(pts, np.array([2, 5]), (Y - V)[[2, 5]])
    assert np.abs(pts - st.apply(Y)).max() <= 1e-13
