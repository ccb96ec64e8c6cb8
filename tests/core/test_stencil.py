"""Stencils W: W @ X equals direct evaluation; locality; regular mode is topology-only.

Locality implied by the construction (stated in gerbs_core.stencil): a sample of
face f depends on the vertices {u} + N_u of f's corners u, N_u the fit data of
l_u = the corners of u's star faces plus up to two layers of faces beyond them.
So moving vertex w changes exactly the samples of the faces in the stars of the
vertices u with w in {u} + N_u. On a triangle mesh N_u lies in the 3-ring of u
(star corners: 1-ring; each extra face layer adds at most one ring), hence only
samples of faces with a vertex in the 3-ring of w can change.
"""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.mesh_surface import BlendingSurface
from gerbs_core.tessellation import Lattice

MESHES = {
    "tri_grid": lambda: P.grid(4, 4, kind="tri"),
    "quad_grid": lambda: P.grid(4, 4),
    "icosphere": lambda: P.icosphere(1),
    "uv_sphere": lambda: P.uv_sphere(8, 6),
    "mixed_bent": lambda: P.mixed_mesh(bend=0.5),
    "delaunay": lambda: P.delaunay_patch(30, 3),
}


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("mode", ["regular", "metric"])
def test_stencil_equals_direct_evaluation(name, mode):
    V, F = MESHES[name]()
    s = BlendingSurface(V, F, mode=mode)
    st = s.stencil(4)
    pts, tris, _ = s.tessellate(4)
    assert st.matrix.shape == (len(pts), len(V))
    assert np.abs(st.apply(V) - pts).max() <= 1e-12
    assert np.array_equal(st.triangles, tris)
    assert np.array_equal(st.vertex_samples, np.arange(len(V)))
    # rows are affine combinations (constants are reproduced)
    assert np.abs(np.asarray(st.matrix.sum(axis=1)).ravel() - 1).max() <= 1e-12
    # new positions: W (bound charts) @ Y == direct evaluation with the same charts
    Y = V + np.random.default_rng(1).normal(scale=0.05, size=V.shape)
    assert np.abs(st.apply(Y) - s.with_positions(Y).tessellate(4)[0]).max() <= 1e-12


def test_regular_stencil_depends_only_on_topology():
    V, F = P.mixed_mesh()
    Y = V + np.random.default_rng(2).normal(scale=0.1, size=V.shape)
    A = BlendingSurface(V, F).stencil(3).matrix
    B = BlendingSurface(Y, F).stencil(3).matrix
    assert (A != B).nnz == 0
    C = BlendingSurface(Y, F, mode="metric").stencil(3).matrix
    assert (A != C).nnz > 0  # metric mode does depend on the rest lengths


def _affected_faces(s, w):
    fits, topo = s.fits, s.topology
    us = [u for u in range(topo.n_vertices) if u == w or w in fits.ids[u]]
    return np.unique(np.concatenate([topo.corner_face[topo.star_corners[
        topo.star_offsets[u]:topo.star_offsets[u + 1]]] for u in us]))


@pytest.mark.parametrize("name", ["icosphere", "mixed_bent", "quad_grid", "delaunay"])
def test_locality_exact(name):
    V, F = MESHES[name]()
    s = BlendingSurface(V, F)
    r = 3
    st = s.stencil(r)
    lat = Lattice(s.topology, r)
    Wc = st.matrix.tocsc()
    topo = s.topology
    for w in range(0, topo.n_vertices, 2):
        rows = Wc.indices[Wc.indptr[w]:Wc.indptr[w + 1]]
        allowed = np.isin(lat.face, _affected_faces(s, w))
        assert allowed[rows].all()
        # moving w changes exactly within the allowed samples
        Y = V.copy()
        Y[w] += [0.03, -0.02, 0.05]
        d = np.abs(s.with_positions(Y).tessellate(r)[0] - s.tessellate(r)[0]).max(axis=1)
        assert np.all(d[~allowed] == 0.0) and d[allowed].max() > 0
        if name == "icosphere":  # topological bound on triangle meshes: the 3-ring
            ring = topo.k_ring(w, 3, include_self=True)
            fv_ok = np.zeros(topo.n_faces, dtype=bool)
            np.logical_or.at(fv_ok, topo.corner_face, np.isin(topo.face_vertices, ring))
            assert fv_ok[lat.face[d > 0]].all()


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
    L = BlendingSurface(V, F).stencil(r).lattice
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
    from gerbs_core.mesh_topology import MeshTopology
    L = Lattice(MeshTopology([[0, 1, 2, 3], [2, 1, 0, 4]], 5), 3)
    ev, ce = L.edges()
    want, corner_keys = _hashed_edges(L)
    got = _edge_keys(L, ev)
    # 3 segments per mesh edge + per quad at r = 3: 2 x 6 inner grid edges + 9 diagonals
    naive = L.topology.n_edges * 3 + 2 * (12 + 9)
    assert len(got) == len(want) == naive - 1  # the repeat was merged, nothing else
    assert np.array_equal(np.sort(got), want) and np.array_equal(got[ce], corner_keys)


def test_stencil_rows_have_sorted_columns_and_no_stored_zeros_beyond_the_locality():
    V, F = P.mixed_mesh(bend=0.5)
    for mode in ("regular", "metric"):
        W = BlendingSurface(V, F, mode=mode).stencil(4).matrix
        rows = np.repeat(np.arange(W.shape[0]), np.diff(W.indptr))
        same_row = rows[1:] == rows[:-1]
        assert np.all(np.diff(W.indices)[same_row] > 0)  # strictly increasing per row
