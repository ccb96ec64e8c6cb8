"""Lattice: shared samples once, no cracks, orientation, exact counts."""
from collections import Counter

import numpy as np
import pytest

from gerbs_core import MeshTopology
from gerbs_core.datasets import primitives
from gerbs_core.errors import InvalidParameterError, ResourceLimitError
from gerbs_core.mesh.lattice import Lattice, output_counts


def _octagon_ring():
    """An octagon ringed by 8 quads, and a regular heptagon on one outer edge (n = 7, 8)."""
    t = 2 * np.pi * np.arange(8) / 8
    inner = np.stack([np.cos(t), np.sin(t), 0 * t], 1)
    outer = np.stack([2.5 * np.cos(t + 0.1), 2.5 * np.sin(t + 0.1), 0.3 + 0 * t], 1)
    faces = [tuple(range(8))]
    for i in range(8):
        j = (i + 1) % 8
        faces.append((j, i, 8 + i, 8 + j))  # traverses the outer edge 8+i -> 8+j
    # heptagon across the outer edge 8 -> 9: walk 9 -> 8 and keep turning left
    pts = [outer[1], outer[0]]
    d = outer[0] - outer[1]
    c, s = np.cos(2 * np.pi / 7), np.sin(2 * np.pi / 7)
    for _ in range(5):
        d = np.array([c * d[0] - s * d[1], s * d[0] + c * d[1], 0.02])
        pts.append(pts[-1] + d)
    v = np.concatenate([inner, outer, pts[2:]])
    faces.append((9, 8, 16, 17, 18, 19, 20))
    return v, faces


MESHES = {
    "icosphere": lambda: primitives.icosphere(1),
    "uv_sphere": lambda: primitives.uv_sphere(6, 4),
    "quad_grid": lambda: primitives.grid(3, 2),
    "tri_grid": lambda: primitives.grid(3, 2, kind="tri"),
    "mixed": lambda: primitives.mixed_mesh(bend=0.3),
    "octagon": _octagon_ring,
}
CLOSED = {"icosphere", "uv_sphere"}


def _build(name, r):
    v, f = MESHES[name]()
    T = MeshTopology(f, len(v))
    return v, T, Lattice(T, r)


def _edge_counts(tri):
    d = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    und = Counter(map(tuple, np.sort(d, 1).tolist()))
    directed = Counter(map(tuple, d.tolist()))
    return und, directed


@pytest.mark.parametrize("name", list(MESHES))
@pytest.mark.parametrize("r", [1, 2, 3, 5])
def test_samples_unique_shared_and_crack_free(name, r):
    v, T, L = _build(name, r)
    X = v[T.face_vertices]  # the piecewise-linear (bilinear on quads) mesh in 3D
    pts = L.map_to_polygon(X)
    assert pts.shape == (L.n_points, 3)
    # no duplicated sample: all mapped positions distinct
    assert len(np.unique(np.round(pts, 9), axis=0)) == L.n_points
    # every occurrence of a sample in every incident face maps to the same point
    loc = L.map_to_polygon(X, local=True)
    np.testing.assert_allclose(loc, pts[L.local_sample], atol=1e-14)
    # each sample is listed by every face incident to it: vertices by their star,
    # edge samples by both faces of the edge
    # (n-gon fans list their corners twice, so count over triangles and quads only)
    if np.all(T.face_sizes <= 4):
        per_sample = np.bincount(L.local_sample, minlength=L.n_points)
        assert np.array_equal(per_sample[:T.n_vertices], np.diff(T.star_offsets))
        es = L.edge_samples.ravel()
        assert np.array_equal(per_sample[es], np.repeat(2 - T.edge_is_boundary, r - 1))
    faces_of = {}
    for f, p in zip(L.local_face.tolist(), L.local_sample.tolist()):
        faces_of.setdefault(p, set()).add(f)
    for e in range(T.n_edges):  # edge samples are listed by exactly the edge's faces
        want = set(T.edge_faces[e][T.edge_faces[e] >= 0].tolist())
        assert all(faces_of[p] == want for p in L.edge_samples[e].tolist())
    # vertex samples are the vertices; edge samples at fractions m / r along each edge
    np.testing.assert_allclose(pts[L.vertex_sample], v, atol=1e-15)
    assert L.edge_samples.shape == (T.n_edges, r - 1)
    a, b = v[T.edges[:, 0]], v[T.edges[:, 1]]
    t = np.arange(1, r) / r
    expect = a[:, None] + t[None, :, None] * (b - a)[:, None]
    np.testing.assert_allclose(pts[L.edge_samples], expect, atol=1e-14)
    # every sample is used by the output triangles, and each face's samples are its own
    assert np.array_equal(np.unique(L.triangles), np.arange(L.n_points))


@pytest.mark.parametrize("name", list(MESHES))
@pytest.mark.parametrize("r", [1, 2, 4])
def test_output_is_watertight_and_oriented_like_the_faces(name, r):
    v, T, L = _build(name, r)
    und, directed = _edge_counts(L.triangles)
    assert max(directed.values()) == 1  # consistent orientation across all triangles
    mult = Counter(und.values())
    boundary = int(T.edge_is_boundary.sum())
    if name in CLOSED:
        assert set(mult) == {2}  # watertight: every output edge in exactly 2 triangles
    else:
        assert mult[1] == r * boundary and set(mult) <= {1, 2}
    # Euler characteristic of the output triangulation equals the mesh's
    chi = L.n_points - len(und) + L.n_triangles
    assert chi == T.euler_characteristic
    # each output triangle's normal agrees with its face's normal (Newell vector)
    pts = L.map_to_polygon(v[T.face_vertices])
    p = pts[L.triangles]
    tn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    fn = np.zeros((T.n_faces, 3))
    for f in range(T.n_faces):
        q = v[T.face(f)] - v[T.face(f)[0]]
        fn[f] = np.cross(q, np.roll(q, -1, 0)).sum(0)
    assert np.all(np.einsum("ij,ij->i", tn, fn[L.triangle_face]) > 0)
    assert np.all(np.diff(L.triangle_face) >= 0)  # grouped by face


@pytest.mark.parametrize("r", [1, 2, 3, 6])
def test_counts_match_closed_forms(r):
    # an icosphere lattice at r has the vertex count of a finer icosphere: 10 (r 2^s)^2 + 2
    v, f = primitives.icosphere(1)
    T = MeshTopology(f, len(v))
    L = Lattice(T, r)
    assert (L.n_points, L.n_triangles) == (10 * (2 * r) ** 2 + 2, 20 * 4 * r * r)
    assert output_counts(T, r) == (L.n_points, L.n_triangles) == (L.n_points, len(L.triangles))
    n, m = 4, 3
    for kind, tris in (("quad", 2), ("tri", 2)):
        v, f = primitives.grid(n, m, kind=kind)
        L = Lattice(MeshTopology(f, len(v)), r)
        assert (L.n_points, L.n_triangles) == ((n * r + 1) * (m * r + 1), tris * n * m * r * r)
    # n-gons: centre + spokes + fan interiors, n r^2 triangles
    v, f = _octagon_ring()
    T = MeshTopology(f, len(v))
    L = Lattice(T, r)
    brute = len(np.unique(np.round(L.map_to_polygon(v[T.face_vertices]), 9), axis=0))
    assert output_counts(T, r)[0] == L.n_points == brute
    assert L.n_triangles == (8 + 7) * r * r + 8 * 2 * r * r


def test_suzanne_resolution_16_counts():
    v, f = primitives.suzanne()
    T = MeshTopology(f, len(v))
    L = Lattice(T, 16)
    P = 507 + T.n_edges * 15 + 468 * 15 ** 2 + 32 * 15 * 14 // 2
    assert L.n_points == P == output_counts(T, 16)[0]
    assert L.n_triangles == 468 * 2 * 256 + 32 * 256
    assert L.face.shape == (P,) and L.uv.shape == (P, 2)


def test_sample_parameters_follow_the_conventions():
    v, T, L = _build("octagon", 4)
    n = T.face_sizes[L.face]
    uv = L.uv
    tri, quad, ngon = n == 3, n == 4, n >= 5
    assert np.all(L.fan[tri | quad] == -1) and np.all((L.fan[ngon] >= 0) & (L.fan[ngon] < n[ngon]))
    assert np.all(uv >= 0) and np.all(uv[quad] <= 1)
    assert np.all(uv[tri | ngon].sum(1) <= 1 + 1e-15)
    # multiples of 1/r
    np.testing.assert_allclose(uv * 4, np.round(uv * 4), atol=1e-12)
    # vertex samples: at a corner of their evaluation face, the first face of the star
    fv, fo = T.face_vertices, T.face_offsets
    first = T.star_faces[T.star_offsets[:-1]]
    assert np.array_equal(L.face[L.vertex_sample], first)
    # reference polygons: a regular unit-side polygon per face; a quad sample at (s, t)
    # maps to the unit square point (s, t) (bilinear is exact there)
    corners = np.zeros((T.n_corners, 2))
    for f in range(T.n_faces):
        k = T.face_sizes[f]
        ang = 2 * np.pi * np.arange(k) / k - np.pi / 2 - np.pi / k
        R = 0.5 / np.sin(np.pi / k)
        corners[fo[f]:fo[f + 1]] = R * np.stack([np.cos(ang), np.sin(ang)], 1)
    q = L.map_to_polygon(corners)
    sq = quad
    c0 = corners[fo[L.face[sq]]]
    np.testing.assert_allclose(q[sq] - c0, uv[sq], atol=1e-14)
    # n-gon samples lie inside their polygon, at the given fan triangle
    ctr = np.zeros((T.n_faces, 2))
    q2 = L.map_to_polygon(corners, centers=ctr)
    np.testing.assert_allclose(q2, q, atol=1e-14)  # regular polygons: centre = mean
    shifted = L.map_to_polygon(corners, centers=ctr + 0.1)
    moved = np.linalg.norm(shifted - q, axis=1) > 1e-12
    assert np.array_equal(moved, ngon & (uv.sum(1) < 1 - 1e-12))
    assert not np.shares_memory(corners, q)


def test_face_groups_and_local_table():
    v, T, L = _build("mixed", 3)
    order, off = L.face_groups()
    for f in (0, 7, T.n_faces - 1):
        assert np.all(L.face[order[off[f]:off[f + 1]]] == f)
    assert off[-1] == L.n_points
    lo = L.local_offsets
    assert np.array_equal(np.repeat(np.arange(T.n_faces), np.diff(lo)), L.local_face)
    for arr in (L.face, L.uv, L.triangles, L.local_uv, L.edge_samples):
        with pytest.raises(ValueError):
            arr[0] = arr[0]


def test_bad_resolution_and_memory_limit():
    v, f = primitives.icosphere(1)
    T = MeshTopology(f, len(v))
    for r in (0, -2, 1.5, True, "4"):
        with pytest.raises(InvalidParameterError) as info:
            Lattice(T, r)
        assert info.value.name == "resolution"
    with pytest.raises(ResourceLimitError) as info:
        Lattice(T, 10, max_points=1000)
    assert str(output_counts(T, 10)[0]) in str(info.value)
    with pytest.raises(InvalidParameterError):
        Lattice(T, 2).map_to_polygon(np.zeros((5, 2)))


def _polygon_edge_keys(L, offsets, corners):
    """Brute force: the key of the edge from each output corner to the next corner of its
    output face, and the sorted distinct keys."""
    nxt = np.arange(len(corners)) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]  # the last corner of each face -> its first
    a, b = corners, corners[nxt]
    key = np.minimum(a, b) * L.n_points + np.maximum(a, b)
    return np.unique(key), key


@pytest.mark.parametrize("name", list(MESHES))
@pytest.mark.parametrize("r", [1, 2, 3])
def test_polygons_are_quads_in_quad_faces_and_the_triangles_elsewhere(name, r):
    v, T, L = _build(name, r)
    off, corners, face, local = L.polygons(quads=False)
    assert np.array_equal(off, 3 * np.arange(L.n_triangles + 1))
    assert np.array_equal(corners, L.triangles.ravel()) and np.array_equal(face, L.triangle_face)
    assert np.array_equal(L.local_sample[local], corners)
    off, corners, face, local = L.polygons()
    sizes = np.diff(off)
    quad = T.face_sizes[face] == 4
    assert np.all(sizes[quad] == 4) and np.all(sizes[~quad] == 3)
    assert np.bincount(face, minlength=T.n_faces).tolist() == np.where(
        T.face_sizes == 4, r * r, np.where(T.face_sizes == 3, r * r, T.face_sizes * r * r)).tolist()
    # each corner is a lattice point of its own face, and the sample it names
    corner_face = np.repeat(face, sizes)
    assert np.array_equal(L.local_face[local], corner_face)
    assert np.array_equal(L.local_sample[local], corners)
    # a quad (a, b, c, d) is exactly the lattice triangles (a, b, c), (a, c, d) of its face
    q = corners[(off[:-1][quad][:, None] + np.arange(4))]
    split = np.sort(np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]), axis=1)
    tq = np.sort(L.triangles[T.face_sizes[L.triangle_face] == 4], axis=1)
    assert np.array_equal(np.unique(split, axis=0), np.unique(tq, axis=0)) and len(split) == len(tq)
    # watertight and consistently oriented; Euler characteristic of the mesh
    nxt = np.arange(len(corners)) + 1
    nxt[off[1:] - 1] = off[:-1]
    directed = Counter(zip(corners.tolist(), corners[nxt].tolist()))
    assert max(directed.values()) == 1
    und = {tuple(sorted(e)) for e in directed}
    assert L.n_points - len(und) + len(face) == T.euler_characteristic
    for a in L.polygons():
        with pytest.raises(ValueError):
            a[0] = a[0]


@pytest.mark.parametrize("name", list(MESHES))
@pytest.mark.parametrize("r", [1, 2, 4])
def test_corner_values_interpolate_per_face_and_are_exact_at_face_corners(name, r):
    """Per-corner values (a UV map with a seam at every edge: random values per face
    corner) carried to the output corners by the corner weights: at a mesh vertex each
    output corner gets its own face's value exactly; inside, the bilinear/barycentric
    blend of its face's corners (constants and the face's own linear data reproduced)."""
    v, T, L = _build(name, r)
    off, corners, face, local = L.polygons()
    W = L.corner_weights(local=True)[local]  # (Co, n_max)
    cf = L.local_face[local]
    fo, sizes = T.face_offsets, T.face_sizes
    slot = np.arange(W.shape[1])
    valid = slot[None, :] < sizes[cf][:, None]
    assert np.all(W[~valid] == 0) and np.allclose(W.sum(1), 1.0, atol=1e-14)
    rng = np.random.default_rng(3)
    values = rng.normal(size=(T.n_corners, 2))
    idx = np.where(valid, fo[cf][:, None] + slot, 0)
    out = np.einsum("ck,ckd->cd", W, values[idx])
    at_vertex = corners < T.n_vertices
    k = np.argmax(valid & (T.face_vertices[idx] == corners[:, None]), axis=1)
    np.testing.assert_array_equal(out[at_vertex], values[idx[at_vertex, k[at_vertex]]])
    # the positions of the face's corners, carried the same way, are map_to_polygon
    Xc = v[T.face_vertices]
    np.testing.assert_allclose(np.einsum("ck,ckd->cd", W, Xc[idx]),
                               L.map_to_polygon(Xc, local=True)[local], atol=1e-14)
    # a broken variant (the weights of the neighbouring lattice point) is caught
    bad = np.einsum("ck,ckd->cd", L.corner_weights(local=True)[np.minimum(local + 1, len(L.local_face) - 1)], values[idx])
    assert not np.array_equal(bad[at_vertex], out[at_vertex])


@pytest.mark.parametrize("name", list(MESHES) + ["valence2"])
@pytest.mark.parametrize("r", [1, 2, 5])
def test_polygon_edges_equal_hashed_edges(name, r):
    if name == "valence2":  # vertex 1 interior with valence 2 (the repeated-edge case)
        T = MeshTopology([[0, 1, 2, 3], [2, 1, 0, 4]], 5)
        L = Lattice(T, r)
    else:
        v, T, L = _build(name, r)
    off, corners, face, local = L.polygons()
    ev, ce = L.edges(quads=True)
    want, corner_keys = _polygon_edge_keys(L, off, corners)
    ev = np.asarray(ev, dtype=np.int64)
    got = np.minimum(ev[:, 0], ev[:, 1]) * L.n_points + np.maximum(ev[:, 0], ev[:, 1])
    assert len(np.unique(got)) == len(got)  # no edge twice
    assert np.array_equal(np.sort(got), want)  # every output face edge, nothing else
    assert ce.shape == corners.shape and np.array_equal(got[ce], corner_keys)
    # the first E r edges are the segments of the mesh edges, in order
    seg = ev[:T.n_edges * r].reshape(T.n_edges, r, 2)
    assert np.array_equal(seg[:, 0, 0], T.edges[:, 0]) and np.array_equal(seg[:, -1, 1], T.edges[:, 1])


def test_corner_weights_of_some_rows_are_as_wide_as_their_faces():
    """(The add-on's transfer and the agreement's cage weights take them per face size: one
    128-gon made every sample's row 128 wide, 3.4 GB beside a 100 x 100 grid.)"""
    X, faces = primitives.mixed_mesh()
    L = Lattice(MeshTopology(faces, len(X)), 3)
    full = L.corner_weights(local=True)
    sizes = L.topology.face_sizes[L.local_face]
    for n in np.unique(sizes).tolist():
        rows = np.flatnonzero(sizes == n)
        part = L.corner_weights(local=True, rows=rows)
        assert part.shape == (len(rows), n)
        np.testing.assert_array_equal(part, full[rows, :n])
        assert not full[rows, n:].any()
