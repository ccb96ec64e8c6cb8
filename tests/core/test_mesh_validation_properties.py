"""Property-based tests (hypothesis) of mesh validation (issue 7 item 1, invalid input).

* random VALID meshes (random Delaunay patches, quad/triangle grids with holes,
  n-gons ringed by quads and triangles, triangle fans, closed bipyramids and
  spheres; randomly relabelled, shuffled and with rotated faces) build, and
  their stars, rings, twins, Euler characteristic and boundary loops agree with
  independent brute-force/geometric checks;
* random CORRUPTIONS of those meshes (one per case) always raise
  InvalidMeshError with the expected tag and the corrupted index among
  ``err.indices`` -- never another exception, never a hang;
* random garbage face lists either build (and then a slow reference checker
  agrees the mesh is valid) or raise InvalidMeshError (and the reference agrees
  it is invalid).

Case counts are fixed by ``max_examples`` below (4,000 generated cases in all).
"""
from collections import defaultdict

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from gerbs_core.datasets import primitives
from gerbs_core.errors import InvalidMeshError
from gerbs_core.mesh import MeshTopology, validate_geometry

SETTINGS = dict(deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow])


# --------------------------------------------------------------- valid meshes
def _grid_with_holes(rng, n, m):
    """Cells are quads or split triangles; holes at odd cells never touch each other."""
    v, _ = primitives.grid(n, m)
    cand = [(i, j) for i in range(1, n - 1, 2) for j in range(1, m - 1, 2)]
    holes = {c for c in cand if rng.random() < 0.5}
    faces = []
    for j in range(m):
        for i in range(n):
            if (i, j) in holes:
                continue
            a = j * (n + 1) + i
            q = (a, a + 1, a + n + 2, a + n + 1)
            r = rng.integers(3)
            if r == 0:
                faces.append(q)
            elif r == 1:
                faces += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
            else:
                faces += [(q[0], q[1], q[3]), (q[1], q[2], q[3])]
    return v, faces, 1 - len(holes), 1 + len(holes)


def _ngon_ring(rng, n):
    """An n-gon surrounded by a ring of quads, some split into triangles."""
    t = 2 * np.pi * np.arange(n) / n
    inner = np.stack([np.cos(t), np.sin(t)], 1)
    outer = 2.5 * np.stack([np.cos(t + 0.2), np.sin(t + 0.2)], 1)
    v = np.concatenate([np.concatenate([inner, outer]), np.zeros((2 * n, 1))], 1)
    faces = [tuple(range(n))]
    for i in range(n):
        q = ((i + 1) % n, i, n + i, n + (i + 1) % n)
        if rng.random() < 0.5:
            faces.append(q)
        else:
            faces += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    return v, faces, 1, 1


def _fan(k, closed):
    t = 2 * np.pi * np.arange(k) / k
    ring = np.stack([np.cos(t), np.sin(t), np.zeros(k)], 1)
    if not closed:
        v = np.concatenate([[[0.0, 0.0, 0.0]], ring])
        return v, [(0, 1 + i, 1 + (i + 1) % k) for i in range(k)], 1, 1
    v = np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]])
    faces = [(0, 1 + i, 1 + (i + 1) % k) for i in range(k)]
    faces += [(k + 1, 1 + (i + 1) % k, 1 + i) for i in range(k)]
    return v, faces, 2, 0


@st.composite
def valid_meshes(draw, closed_ok=True):
    """(vertices (V,3), faces list, chi, n_boundary_loops, flat)."""
    kinds = ["delaunay", "grid", "ngon", "fan"] + (["bipyramid", "sphere"] if closed_ok else [])
    kind = draw(st.sampled_from(kinds))
    event(f"mesh: {kind}")
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    flat = True
    if kind == "delaunay":
        v, f = primitives.delaunay_patch(draw(st.integers(4, 40)), int(rng.integers(2**31)))
        f, chi, loops = [tuple(x) for x in f.tolist()], 1, 1
    elif kind == "grid":
        v, f, chi, loops = _grid_with_holes(rng, draw(st.integers(1, 7)), draw(st.integers(2, 7)))
    elif kind == "ngon":
        v, f, chi, loops = _ngon_ring(rng, draw(st.integers(3, 12)))
    elif kind == "fan":
        v, f, chi, loops = _fan(draw(st.integers(3, 20)), closed=False)
    elif kind == "bipyramid":
        v, f, chi, loops = _fan(draw(st.integers(3, 20)), closed=True)
        flat = False
    else:
        if draw(st.booleans()):
            v, f = primitives.icosphere(draw(st.integers(0, 1)))
            f = [tuple(x) for x in f.tolist()]
        else:
            v, f = primitives.uv_sphere(draw(st.integers(3, 9)), draw(st.integers(2, 6)))
        chi, loops, flat = 2, 0, False
    # random relabelling, face order and starting corners: validity is invariant
    perm = rng.permutation(len(v))
    v2 = np.empty_like(v)
    v2[perm] = v
    faces = []
    for i in rng.permutation(len(f)):
        face = [int(perm[x]) for x in f[i]]
        s = int(rng.integers(len(face)))
        faces.append(tuple(face[s:] + face[:s]))
    return v2, faces, chi, loops, flat


def _check_topology(T, v, faces, chi, loops, flat):
    V = len(v)
    fv, so, sc = T.face_vertices, T.star_offsets, T.star_corners
    nxt, prv, twin = T.corner_next, T.corner_prev, T.halfedge_twin
    assert T.n_vertices == V and T.n_faces == len(faces)
    assert [tuple(x) for x in T.faces_as_list()] == faces
    assert T.euler_characteristic == chi
    assert len(T.boundary_loops) == loops
    # twins: an involution between opposite half-edges
    t = twin >= 0
    assert np.array_equal(twin[twin[t]], np.flatnonzero(t))
    assert np.array_equal(fv[twin[t]], fv[nxt[t]]) and np.array_equal(fv[nxt[twin[t]]], fv[t])
    assert int((~t).sum()) == sum(len(l) for l in T.boundary_loops)
    # every star is a permutation of the corners at v, ordered by shared spokes
    assert np.array_equal(np.sort(sc), np.arange(T.n_corners))
    assert np.array_equal(fv[sc], np.repeat(np.arange(V), np.diff(so)))
    for x in range(V):
        s = T.star(x)
        assert np.array_equal(fv[prv[s[:-1]]], fv[nxt[s[1:]]])
        if T.vertex_is_boundary[x]:
            assert twin[s[0]] < 0 and twin[prv[s[-1]]] < 0
        else:
            assert fv[prv[s[-1]]] == fv[nxt[s[0]]]  # a closed cycle
        ring = T.one_ring(x)
        assert len(set(ring.tolist())) == len(ring) == T.vertex_valence[x]
        if flat:  # geometric check of the counter-clockwise order
            d = v[ring, :2] - v[x, :2]
            ang = np.arctan2(d[:, 1], d[:, 0])
            inc = np.mod(np.diff(np.r_[ang, ang[0]] if not T.vertex_is_boundary[x] else ang), 2 * np.pi)
            assert np.all((inc > 0) & (inc < np.pi))
            if not T.vertex_is_boundary[x]:
                assert abs(inc.sum() - 2 * np.pi) < 1e-9
    # edges: brute force
    und = {tuple(sorted((f[k], f[(k + 1) % len(f)]))) for f in faces for k in range(len(f))}
    assert sorted(und) == [tuple(e) for e in T.edges.tolist()]


@settings(max_examples=600, **SETTINGS)
@given(valid_meshes())
def test_random_valid_meshes_build_with_consistent_stars(mesh):
    v, faces, chi, loops, flat = mesh
    v_copy = v.copy()
    T = MeshTopology(faces, len(v))
    validate_geometry(v, T)
    _check_topology(T, v, faces, chi, loops, flat)
    assert np.array_equal(v, v_copy)
    # the (F,k) array input gives the same topology when all faces have one size
    if len({len(f) for f in faces}) == 1:
        arr = np.array(faces)
        T2 = MeshTopology(arr, len(v))
        assert np.array_equal(T2.star_corners, T.star_corners)
        assert np.array_equal(arr, np.array(faces))


# ---------------------------------------------------------------- corruptions
TOPOLOGY_CORRUPTIONS = ["non_manifold_edge", "inconsistent_orientation", "non_manifold_vertex",
                        "duplicate_face", "repeated_index", "degenerate_face",
                        "index_out_of_range", "unused_vertex", "empty", "bad_shape"]


def _corrupt(kind, rng, v, faces):
    """Apply one corruption. Returns (vertices, faces, n_vertices, expected index, attribute)."""
    V, F = len(v), len(faces)
    faces = list(faces)
    if kind == "non_manifold_edge":
        T = MeshTopology(faces, V)
        inner = np.flatnonzero(~T.edge_is_boundary)
        a, b = T.edges[inner[rng.integers(len(inner))]]
        v = np.concatenate([v, [[9.0, 9.0, 9.0]]])
        faces.append((int(b), int(a), V))
        return v, faces, V + 1, int(a), "indices"
    if kind == "inconsistent_orientation":
        T = MeshTopology(faces, V)
        f = int(rng.integers(F))  # every face of these meshes has an interior edge
        faces[f] = faces[f][::-1]
        return v, faces, V, f, "faces"
    if kind == "non_manifold_vertex":
        # glue a separate triangle fan to vertex x by one of its rim vertices
        x = int(rng.integers(V))
        k = int(rng.integers(3, 7))
        new = list(range(V, V + k))
        fan = [(new[0], new[i], new[i + 1]) for i in range(1, k - 1)]
        fan = [tuple(x if w == new[-1] else w for w in f) for f in fan]
        v = np.concatenate([v, rng.normal(size=(k - 1, 3)) + 5.0])
        return v, faces + fan, V + k - 1, x, "indices"
    if kind == "duplicate_face":
        f = int(rng.integers(F))
        g = list(faces[f])
        s = int(rng.integers(len(g)))
        g = g[s:] + g[:s]
        faces.insert(int(rng.integers(F + 1)), tuple(g[::-1] if rng.random() < 0.5 else g))
        return v, faces, V, None, "indices"
    if kind == "repeated_index":
        f = int(rng.integers(F))
        g = list(faces[f])
        g.insert(int(rng.integers(len(g) + 1)), g[int(rng.integers(len(g)))])
        faces[f] = tuple(g)
        return v, faces, V, f, "indices"
    if kind == "degenerate_face":
        f = int(rng.integers(F))
        g = faces[f]
        faces[f] = (g[0], g[1]) if rng.random() < 0.5 else (g[0], g[1], g[0])
        return v, faces, V, f, "indices"
    if kind == "index_out_of_range":
        f = int(rng.integers(F))
        g = list(faces[f])
        g[int(rng.integers(len(g)))] = int(V + rng.integers(5)) if rng.random() < 0.5 else -1
        faces[f] = tuple(g)
        return v, faces, V, f, "indices"
    if kind == "unused_vertex":
        extra = int(rng.integers(1, 4))
        return v, faces, V + extra, V + extra - 1, "indices"
    if kind == "empty":
        choice = int(rng.integers(3))
        if choice == 0:
            return v, [], V, None, None
        if choice == 1:
            return v, np.zeros((0, 3), dtype=np.int64), V, None, None
        return v, faces, 0, None, None
    # bad_shape
    choice = int(rng.integers(4))
    if choice == 0:
        return v, np.arange(6), V, None, None
    if choice == 1:
        return v, np.array(faces[:1], dtype=np.float64), V, None, None
    if choice == 2:
        return v, faces[:-1] + [7], V, None, None
    return v, faces[:-1] + [(0, 1.5, 2)], V, None, None


@settings(max_examples=1800, **SETTINGS)
@given(valid_meshes(), st.sampled_from(TOPOLOGY_CORRUPTIONS), st.integers(0, 2**32 - 1))
def test_random_topological_corruptions_raise_the_right_tag(mesh, kind, seed):
    v, faces, *_ = mesh
    event(f"corruption: {kind}")
    rng = np.random.default_rng(seed)
    v, bad, nv, index, attr = _corrupt(kind, rng, v, faces)
    frozen = [tuple(f) for f in bad] if isinstance(bad, list) and kind != "bad_shape" else None
    with pytest.raises(InvalidMeshError) as info:
        MeshTopology(bad, nv)
    err = info.value
    assert err.problem == kind, (err.problem, str(err))
    if kind == "duplicate_face":
        assert len(err.indices) >= 2
        dup = [bad[i] for i in err.indices]
        assert len({tuple(sorted(f)) for f in dup}) < len(dup)
    elif index is not None:
        assert index in getattr(err, attr), (index, str(err))
        assert str(index) in str(err)
    if frozen is not None:
        assert [tuple(f) for f in bad] == frozen  # the caller's faces are untouched


GEOMETRY_CORRUPTIONS = ["non_finite", "zero_length_edge", "degenerate_face"]


@settings(max_examples=600, **SETTINGS)
@given(valid_meshes(closed_ok=False), st.sampled_from(GEOMETRY_CORRUPTIONS),
       st.integers(0, 2**32 - 1))
def test_random_geometric_corruptions_raise_the_right_tag(mesh, kind, seed):
    v, faces, *_ = mesh
    event(f"corruption: {kind}")
    rng = np.random.default_rng(seed)
    T = MeshTopology(faces, len(v))
    x = v.copy()
    if kind == "non_finite":
        i = int(rng.integers(len(x)))
        x[i, int(rng.integers(3))] = [np.nan, np.inf, -np.inf][int(rng.integers(3))]
        expect = i
    elif kind == "zero_length_edge":
        a, b = T.edges[int(rng.integers(T.n_edges))]
        x[a] = x[b]
        expect = int(a)
    else:  # move all corners of one face onto a line (distinct points)
        f = int(rng.integers(T.n_faces))
        c = T.face(f)
        d = rng.normal(size=3)
        x[c] = x[c[0]] + np.linspace(0.0, 1.0, len(c))[:, None] * d
        expect = f
    before = x.copy()
    with pytest.raises(InvalidMeshError) as info:
        validate_geometry(x, T)
    assert info.value.problem == kind
    assert expect in info.value.indices
    assert np.array_equal(x, before, equal_nan=True)


# ----------------------------------------------------------- garbage face lists
def _reference_valid(faces, V):
    """Slow, independent check that faces form an oriented manifold using all V vertices."""
    if not faces or V == 0:
        return False
    seen_sets, directed, undirected = set(), set(), defaultdict(int)
    used = set()
    around = defaultdict(list)
    for fi, f in enumerate(faces):
        if len(set(f)) != len(f) or len(f) < 3 or min(f) < 0 or max(f) >= V:
            return False
        key = tuple(sorted(f))
        if key in seen_sets:
            return False
        seen_sets.add(key)
        for k in range(len(f)):
            a, b = f[k], f[(k + 1) % len(f)]
            if (a, b) in directed:
                return False
            directed.add((a, b))
            undirected[frozenset((a, b))] += 1
            around[a].append((fi, f[k - 1], b))
        used.update(f)
    if any(c > 2 for c in undirected.values()) or len(used) != V:
        return False
    for x, corners in around.items():  # the faces at x must be connected through spokes
        comp = {0}
        changed = True
        while changed:
            changed = False
            for i, (_, p, n) in enumerate(corners):
                if i in comp:
                    continue
                if any({p, n} & {corners[j][1], corners[j][2]} for j in comp):
                    comp.add(i)
                    changed = True
        if len(comp) != len(corners):
            return False
    return True


@settings(max_examples=1000, **SETTINGS)
@given(st.integers(3, 7).flatmap(lambda V: st.tuples(
    st.just(V),
    st.lists(st.lists(st.integers(0, V - 1), min_size=3, max_size=4, unique=True),
             min_size=1, max_size=8),  # plausible faces
    st.lists(st.lists(st.integers(-1, V), max_size=5), max_size=1),  # maybe one garbage face
    st.integers(0, 8))))
def test_garbage_faces_build_or_raise_consistently(case):
    """Random small face lists: build iff a slow reference checker says valid."""
    V, faces, garbage, at = case
    faces = [tuple(f) for f in faces]
    faces[at:at] = [tuple(f) for f in garbage]
    try:
        T = MeshTopology(faces, V)
    except InvalidMeshError as err:
        assert err.problem in TOPOLOGY_CORRUPTIONS
        event(f"raised {err.problem}")
        assert not _reference_valid(faces, V), str(err)
        return
    event("valid")
    assert _reference_valid(faces, V)
    assert np.array_equal(np.sort(T.star_corners), np.arange(T.n_corners))
