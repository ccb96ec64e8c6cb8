"""A creased surface's factored outputs: the partition of unity names the repaired mesh's
vertices (not the cut mesh's copies), and the stencil's coefficient operator (the fits of
the copies summed per vertex) gives the same points as applying the fits directly, with
moves through it exact and a zero move changing nothing.
"""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.mesh.surface import BlendingSurface
from gerbs_core.mesh.topology import MeshTopology


@pytest.fixture(scope="module")
def creased():
    V, F = P.cube()
    T = MeshTopology(F, len(V))
    creases = {tuple(int(i) for i in e): 1.0 for e in T.edges[:5]}
    return V, BlendingSurface(V, F, creases=creases)


def test_partition_of_a_creased_surface_names_the_mesh_vertices(creased):
    V, s = creased
    T = s.topology
    assert s.model.topology.n_vertices > T.n_vertices      # the cut has vertex copies
    verts, Psi, psi = s.partition(T.corner_face, s.layouts.corners)
    np.testing.assert_allclose(Psi.sum(axis=1), 1.0, atol=1e-13)
    assert Psi.min() >= -1e-15 and psi.max() <= 1.0 + 1e-15
    assert verts.max() < T.n_vertices
    at = np.argmax(Psi, axis=1)
    np.testing.assert_allclose(Psi[np.arange(len(at)), at], 1.0, atol=1e-13)
    np.testing.assert_array_equal(verts[np.arange(len(at)), at], T.face_vertices)
    # inside a face: the face's own corners carry the weights
    x = 0.2 * s.layouts.corners[T.face_offsets[2]:T.face_offsets[3]].mean(0, keepdims=True)
    v, w, _ = s.partition([2], x)
    assert set(v[0][w[0] > 0].tolist()) <= set(T.face_vertices[T.face_offsets[2]:
                                                                T.face_offsets[3]].tolist())


def test_creased_stencil_operator_gives_the_direct_points(creased):
    V, s = creased
    st = s.stencil(4)
    X = V + np.random.default_rng(0).normal(0.0, 0.05, V.shape)
    direct = st.apply(X)                                   # fits applied to X[copy_of]
    np.testing.assert_allclose(st.matrix() @ X, direct, atol=1e-12)
    assert st.nnz_per_row() == pytest.approx(st.nnz / st.shape[0])


def test_moves_through_the_built_operator_are_exact(creased):
    V, s = creased
    st = s.stencil(4)
    _ = st.matrix()                       # builds the operator: columns() then slices it
    assert st.fits.operator_built
    P0 = st.apply(V)
    moved = np.array([0, 6])
    delta = np.array([[0.1, 0.0, -0.05], [0.0, 0.2, 0.0]])
    X1 = V.copy()
    X1[moved] += delta
    pts = P0.copy()
    st.apply_moved(pts, moved, delta)
    np.testing.assert_allclose(pts, st.apply(X1), atol=1e-12)
    same = P0.copy()
    st.apply_moved(same, moved, np.zeros((2, 3)))
    np.testing.assert_array_equal(same, P0)
