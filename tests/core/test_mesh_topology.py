"""MeshTopology: connectivity, ordered stars, and validation of hand-made bad meshes."""
import numpy as np
import pytest

from gerbs_core import MeshTopology
from gerbs_core.datasets import primitives
from gerbs_core.errors import InvalidMeshError
from gerbs_core.mesh.validation import validate_geometry


def _raises(problem, faces, n_vertices=None):
    with pytest.raises(InvalidMeshError) as info:
        MeshTopology(faces, n_vertices)
    assert info.value.problem == problem, str(info.value)
    assert problem in str(info.value)
    return info.value


def _cyclic_equal(a, b):
    a, b = list(a), list(b)
    return len(a) == len(b) and any(a[k:] + a[:k] == b for k in range(len(a)))


# ------------------------------------------------------------------ validation
def test_bad_shape():
    err = _raises("bad_shape", np.arange(6))
    assert "shape" in str(err)
    _raises("bad_shape", np.array([[0.0, 1.0, 2.0]]))
    err = _raises("bad_shape", [(0, 1, 2), 5, (1, 2, 3)])
    assert err.indices == (1,) and err.element == "face"
    err = _raises("bad_shape", [(0, 1, 2), (1, 2, 3), (0, "a", 3)])
    assert err.indices == (2,)
    _raises("bad_shape", [(0, 1, 2)], n_vertices=-1)
    _raises("bad_shape", [(0, 1, 2)], n_vertices=2.5)
    _raises("bad_shape", 17)


def test_empty():
    _raises("empty", [])
    _raises("empty", np.zeros((0, 3), dtype=int))
    _raises("empty", [(0, 1, 2)], n_vertices=0)


def test_index_out_of_range_names_faces_and_values():
    err = _raises("index_out_of_range", [(0, 1, 2), (2, 1, 5), (0, 2, 3)], n_vertices=4)
    assert err.indices == (1,) and err.element == "face" and "5" in str(err)
    err = _raises("index_out_of_range", np.array([[0, 1, 2], [-1, 2, 1]]), n_vertices=3)
    assert err.indices == (1,) and "-1" in str(err)


def test_degenerate_and_repeated_index():
    err = _raises("degenerate_face", [(0, 1, 2), (2, 1)])
    assert err.indices == (1,)
    err = _raises("degenerate_face", [(0, 1, 2), (2, 1, 3), (3, 1, 3)])
    assert err.indices == (2,)
    err = _raises("repeated_index", [(0, 1, 2, 1, 3), (1, 4, 2)])
    assert err.indices == (0,)


def test_duplicate_faces_in_any_rotation_or_orientation():
    err = _raises("duplicate_face", [(0, 1, 2), (2, 1, 3), (1, 2, 0)])
    assert err.indices == (0, 2)
    err = _raises("duplicate_face", [(0, 1, 2, 3), (3, 2, 1, 0), (1, 4, 2)])
    assert err.indices == (0, 1)


def test_non_manifold_edge():
    err = _raises("non_manifold_edge", [(0, 1, 2), (1, 0, 3), (0, 1, 4)])
    assert err.indices == (0, 1) and err.element == "vertex"
    assert err.edges == [(0, 1)] and err.faces == [0, 1, 2]
    assert "(0, 1)" in str(err)


def test_inconsistent_orientation_and_moebius_strip():
    err = _raises("inconsistent_orientation", [(0, 1, 2), (0, 1, 3)])
    assert err.edges == [(0, 1)] and err.faces == [0, 1]
    # a flipped face in a grid
    v, f = primitives.grid(3, 3)
    f = f.copy()
    f[4] = f[4][::-1]
    err = _raises("inconsistent_orientation", f)
    assert 4 in err.faces and len(err.edges) == 4
    # Moebius strip: a band of 6 quads closed with a half twist is not orientable
    n = 6
    top, bot = list(range(n)), list(range(n, 2 * n))
    faces = [(top[i], top[i + 1], bot[i + 1], bot[i]) for i in range(n - 1)]
    faces.append((top[n - 1], bot[0], top[0], bot[n - 1]))  # glue with a half twist
    err = _raises("inconsistent_orientation", faces)
    # without the twist it is a valid annulus
    ok = faces[:-1] + [(top[n - 1], top[0], bot[0], bot[n - 1])]
    T = MeshTopology(ok)
    assert T.euler_characteristic == 0 and len(T.boundary_loops) == 2


def test_bow_tie_vertices():
    err = _raises("non_manifold_vertex", [(0, 1, 2), (0, 3, 4)])
    assert err.indices == (0,) and err.element == "vertex"
    # two closed cones (tetrahedra) sharing an apex: two closed fans
    tet = [(0, 2, 1), (0, 3, 2), (0, 1, 3), (1, 2, 3)]
    other = [tuple(0 if x == 0 else x + 3 for x in f) for f in tet]
    err = _raises("non_manifold_vertex", tet + other)
    assert err.indices == (0,)
    # a closed fan plus an open fan at vertex 0
    err = _raises("non_manifold_vertex", tet + [(0, 7, 8)])
    assert err.indices == (0,)


def test_unused_vertices():
    err = _raises("unused_vertex", [(0, 1, 2)], n_vertices=5)
    assert err.indices == (3, 4) and err.element == "vertex"
    err = _raises("unused_vertex", [(0, 1, 3)])
    assert err.indices == (2,)


def test_huge_vertex_counts_fail_fast():
    err = _raises("unused_vertex", [(0, 1, 2)], n_vertices=10**15)
    assert err.indices[:3] == (3, 4, 5)
    err = _raises("unused_vertex", [(0, 1, 10**12), (1, 0, 3)])
    assert err.indices[:2] == (2, 4)


def test_checks_run_in_the_documented_order():
    # out of range is reported before the duplicate, duplicates before non-manifold edges
    _raises("index_out_of_range", [(0, 1, 2), (0, 1, 2), (0, 1, 9)], n_vertices=4)
    _raises("duplicate_face", [(0, 1, 2), (1, 0, 3), (0, 1, 2)])
    _raises("non_manifold_edge", [(0, 1, 2), (1, 0, 3), (0, 1, 4)], n_vertices=7)


def test_geometry_validation_tags_and_tolerance():
    v, f = primitives.grid(3, 3, kind="tri")
    T = MeshTopology(f, len(v))
    validate_geometry(v, T)
    validate_geometry(v[:, :2], T)
    x = v.copy()
    x[5, 1] = np.nan
    x[9, 2] = np.inf
    with pytest.raises(InvalidMeshError) as info:
        validate_geometry(x, T)
    assert info.value.problem == "non_finite" and info.value.indices == (5, 9)
    x = v.copy()
    x[5] = x[6]
    with pytest.raises(InvalidMeshError) as info:
        validate_geometry(x, T)
    assert info.value.problem == "zero_length_edge" and info.value.edges == [(5, 6)]
    assert info.value.indices == (5, 6)
    # collinear triangle: move vertex 0 onto the line through its face's other corners
    x = v.copy()
    f0 = T.face(0)
    x[f0[0]] = 2 * x[f0[1]] - x[f0[2]]
    with pytest.raises(InvalidMeshError) as info:
        validate_geometry(x, T)
    assert info.value.problem == "degenerate_face" and 0 in info.value.indices
    with pytest.raises(InvalidMeshError) as info:
        validate_geometry(v[:-1], T)
    assert info.value.problem == "bad_shape"
    # slivers with a 0.01 degree angle and extreme scales are accepted; at 1e-5 degrees
    # the edge lengths admit no convex polygon to 1e-12 (what the layout needs): refused
    x = v.copy()
    x[f0[0]] = x[f0[1]] + 10 * (x[f0[2]] - x[f0[1]]) + [0, 0, np.tan(1e-2 * np.pi / 180)]
    validate_geometry(x, T)
    x[f0[0]] = x[f0[1]] + 10 * (x[f0[2]] - x[f0[1]]) + [0, 0, np.tan(1e-5 * np.pi / 180)]
    with pytest.raises(InvalidMeshError) as info:
        validate_geometry(x, T)
    assert info.value.problem == "degenerate_face" and info.value.indices == (0,)
    x = v.copy()
    for scale in (1e-6, 1e6):
        validate_geometry(v * scale + 3 * scale, T)


def test_caller_arrays_untouched_and_topology_immutable():
    v, f = primitives.grid(3, 2)
    f_copy = f.copy()
    T = MeshTopology(f, len(v))
    assert np.array_equal(f, f_copy) and f.flags.writeable
    assert not np.shares_memory(T.face_vertices, f)
    for name in ("face_vertices", "face_offsets", "edges", "star_corners", "halfedge_twin",
                 "vertex_is_boundary", "ring_vertices"):
        arr = getattr(T, name)
        with pytest.raises(ValueError):
            arr[0] = arr[0]
    with pytest.raises(AttributeError):
        T.n_vertices = 3
    faces = [[0, 1, 2], [0, 2, 3]]
    MeshTopology(faces)
    assert faces == [[0, 1, 2], [0, 2, 3]]


def test_integer_dtypes_and_lists_of_arrays():
    v, f = primitives.icosphere(1)
    ref = MeshTopology(f)
    for ff in (f.astype(np.uint32), f.astype(np.int32), list(f), [tuple(x) for x in f.tolist()]):
        T = MeshTopology(ff, len(v))
        assert np.array_equal(T.star_corners, ref.star_corners)
        assert np.array_equal(T.edges, ref.edges)


# --------------------------------------------------------------- connectivity
def test_quad_grid_stars_and_rings_by_hand():
    v, f = primitives.grid(2, 2)  # vertex (i, j) = 3 j + i; face (i, j) = 2 j + i
    T = MeshTopology(f, len(v))
    assert _cyclic_equal(T.one_ring(4), [5, 7, 3, 1])  # counter-clockwise from +z
    assert _cyclic_equal(T.star_faces[T.star_offsets[4]:T.star_offsets[5]], [1, 3, 2, 0])
    assert not T.vertex_is_boundary[4]
    # boundary vertex 1 (bottom middle): open fan from edge 1->2 round to edge 0->1
    assert T.vertex_is_boundary[1]
    assert T.one_ring(1).tolist() == [2, 4, 0]
    assert T.star_faces[T.star_offsets[1]:T.star_offsets[2]].tolist() == [1, 0]
    assert T.one_ring(0).tolist() == [1, 3] and T.vertex_valence[0] == 2
    assert T.vertex_valence.tolist() == [2, 3, 2, 3, 4, 3, 2, 3, 2]
    (loop,) = T.boundary_loops
    assert _cyclic_equal(loop, [0, 1, 2, 5, 8, 7, 6, 3])  # mesh on the left


def test_boundary_loops_of_a_grid_with_a_hole_are_oriented():
    v, f = primitives.grid(3, 3)
    f = np.delete(f, 4, axis=0)  # the centre cell
    T = MeshTopology(f, len(v))
    assert T.euler_characteristic == 0
    areas = []
    for loop in T.boundary_loops:
        p = v[loop, :2]
        areas.append(0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))
    np.testing.assert_allclose(sorted(areas), [-1 / 9, 1.0], rtol=1e-12)  # outer ccw, hole cw
    assert int(T.edge_is_boundary.sum()) == 16


def test_edges_twins_and_face_adjacency():
    v, f = primitives.mixed_mesh()
    T = MeshTopology(f, len(v))
    assert T.n_edges == T.n_vertices + T.n_faces - T.euler_characteristic
    e = T.edges
    assert np.all(e[:, 0] < e[:, 1]) and len(np.unique(e, axis=0)) == T.n_edges
    h = T.edge_halfedges
    fv, nxt = T.face_vertices, T.corner_next
    ends = np.sort(np.stack([fv[h[:, 0]], fv[nxt[h[:, 0]]]], 1), axis=1)
    assert np.array_equal(ends, e)
    assert np.array_equal(T.edge_is_boundary, h[:, 1] < 0)
    assert np.array_equal(T.halfedge_edge[h[:, 0]], np.arange(T.n_edges))
    A = T.face_adjacency
    assert (A != A.T).nnz == 0
    inner_edges = np.bincount(T.corner_face[T.halfedge_twin >= 0], minlength=T.n_faces)
    assert np.array_equal(np.asarray(A.sum(1)).ravel(), inner_edges)
    hexa = int(np.flatnonzero(T.face_sizes == 6)[0])
    nb = T.face_neighbors(hexa)
    assert len(nb) == 6 and all(A[hexa, g] for g in nb if g >= 0)


def test_k_rings_on_a_grid():
    v, f = primitives.grid(6, 6)
    T = MeshTopology(f, len(v))
    c = 3 * 7 + 3  # centre vertex (3, 3)
    assert T.k_ring(c, 1).tolist() == sorted([c - 1, c + 1, c - 7, c + 7])
    ring2 = T.k_ring(c, 2)
    ij = np.stack([ring2 % 7, ring2 // 7], 1)
    assert np.all(np.abs(ij - 3).sum(1) <= 2) and len(ring2) == 12  # a diamond, without c
    assert c in T.k_ring(c, 2, include_self=True)
    assert len(T.face_k_ring(c, 1)) == 4
    assert len(T.face_k_ring(c, 2)) == 16  # the 4 x 4 block of cells
    assert len(T.face_k_ring(c, 3)) == 36
    assert T.face_k_ring(0, 1).tolist() == [0]


def test_suzanne_stars_are_consistent():
    v, f = primitives.suzanne()
    T = MeshTopology(f, len(v))
    fv, prv, nxt = T.face_vertices, T.corner_prev, T.corner_next
    for x in range(T.n_vertices):
        s = T.star(x)
        assert np.all(fv[s] == x)
        assert np.array_equal(fv[prv[s[:-1]]], fv[nxt[s[1:]]])
    assert T.euler_characteristic == 2  # head with eye holes plus two eyes
