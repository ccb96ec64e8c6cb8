"""Flipped triangulations of obtuse triangles (lattice_templates.flipped_triangles): the
same samples, a valid triangulation with smaller angles, consistent faces and edges."""
from collections import Counter

import numpy as np
import pytest

from gerbs_core import BlendingSurface, FairnessRule, MeshTopology
from gerbs_core.datasets import primitives
from gerbs_core.errors import InvalidParameterError
from gerbs_core.mesh.lattice import Lattice
from gerbs_core.mesh.lattice_templates import (FLIP_ANGLE, flipped_triangles, obtuse_flips,
                                               template, template_edges)
from gerbs_core.mesh.layout import face_layouts


def _angles(p):
    """(T, 3) angles (degrees) of triangles p (T, 3, d)."""
    out = []
    for k in range(3):
        a, b = p[:, (k + 1) % 3] - p[:, k], p[:, (k + 2) % 3] - p[:, k]
        c = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        out.append(np.degrees(np.arccos(np.clip(c, -1, 1))))
    return np.stack(out, 1)


@pytest.mark.parametrize("r", [1, 2, 3, 6])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_flipped_triangles_triangulate_the_lattice(r, k):
    uv = template(3, r)[0]
    t = flipped_triangles(r, k)
    p = uv[t]
    area = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]) / 2
    assert len(t) == r * r and np.all(area > 0)  # counter-clockwise, like the face
    np.testing.assert_allclose(area.sum(), 0.5, rtol=1e-13)  # they tile the triangle ...
    assert len(np.unique(np.sort(t, 1), axis=0)) == r * r  # ... without repeats
    assert set(t.ravel().tolist()) == set(range(len(uv)))  # every sample used
    # the same number of inner edges as the lattice's own (the edge numbering relies on it)
    assert (template_edges(3, r, False, k)[2] < 0).sum() == (template_edges(3, r)[2] < 0).sum()
    corner = np.flatnonzero((template(3, r)[2] == 0) & (template(3, r)[3] == k))[0]
    if r >= 2:  # the corner triangle at k is split at c = p + q - k, on its bisector
        at = t[(t == corner).any(1)]
        bary = np.concatenate([1 - uv.sum(1, keepdims=True), uv], 1)
        assert len(at) == 2 and any(np.isclose(bary[at.ravel(), k], 1 - 2 / r).tolist())


@pytest.mark.parametrize("k", [0, 1, 2])
@pytest.mark.parametrize("big", [115.0, 140.0, 164.0])
def test_flipped_face_has_smaller_largest_angles(k, big):
    """A triangle with a `big` corner at k (isosceles): the lattice's own r^2 triangles
    all have that angle (in layout coordinates); flipped, only the r along the long side
    keep it (their long edge is a segment of that side: nothing else can close them) and
    every other is the half of a rhombus, angles (big/2, 180 - big, big/2); the flip at
    another corner is worse."""
    small = (180.0 - big) / 2
    ang = np.roll(np.radians([big, small, small]), k)
    t = np.cumsum(2 * np.roll(ang, -1))  # corners on the unit circle: inscribed angles
    X = np.stack([np.cos(t), np.sin(t), 0 * t], 1)
    T = MeshTopology([[0, 1, 2]], 3)
    lay = face_layouts(T, X)
    np.testing.assert_allclose(np.degrees(lay.angles[k]), big, atol=1e-9)
    assert obtuse_flips(T, lay.angles).tolist() == ([k] if big > FLIP_ANGLE else [-1])
    assert obtuse_flips(T, lay.angles, 100.0).tolist() == [k]
    assert obtuse_flips(T, lay.angles, 170.0).tolist() == [-1]
    for r in (2, 4, 8):
        worst = {}
        for f in (-1, 0, 1, 2):
            L = Lattice(T, r, flip=[f])
            worst[f] = np.sort(_angles(L.map_to_polygon(lay.corners)[L.triangles]).max(1))
        np.testing.assert_allclose(worst[-1], big, atol=1e-9)
        np.testing.assert_allclose(worst[k][-r:], big, atol=1e-9)
        np.testing.assert_allclose(worst[k][:-r], max(big / 2, 180 - big), atol=1e-9)
        assert all(worst[f].sum() > worst[k].sum() for f in (0, 1, 2) if f != k)


def _flipped(name, r, seed=0):
    v, f = {"icosphere": lambda: primitives.icosphere(1),
            "mixed": lambda: primitives.mixed_mesh(bend=0.3)}[name]()
    T = MeshTopology(f, len(v))
    rng = np.random.default_rng(seed)
    flip = np.where(T.face_sizes == 3, rng.integers(-1, 3, T.n_faces), -1)
    assert len(set(flip[T.face_sizes == 3].tolist())) == 4  # every variant, mixed in a class
    return T, Lattice(T, r), Lattice(T, r, flip=flip)


@pytest.mark.parametrize("name", ["icosphere", "mixed"])
@pytest.mark.parametrize("r", [1, 2, 3, 5])
def test_flipped_lattice_is_a_closed_manifold_with_consistent_faces_and_edges(name, r):
    T, L0, L = _flipped(name, r)
    # the samples and the local table are untouched
    for a in ("local_sample", "local_offsets", "face", "uv", "fan", "local_uv"):
        assert np.array_equal(getattr(L, a), getattr(L0, a))
    assert np.array_equal(L.triangle_face, L0.triangle_face)
    changed = np.any(L.triangles != L0.triangles, axis=1)
    assert (r == 1 or changed.any()) and np.all(L.flip[L.triangle_face[changed]] >= 0)
    assert set(L.triangles.ravel().tolist()) == set(range(L.n_points))  # every sample used
    d = np.concatenate([L.triangles[:, [0, 1]], L.triangles[:, [1, 2]], L.triangles[:, [2, 0]]])
    assert max(Counter(map(tuple, d.tolist())).values()) == 1  # oriented
    mult = Counter(Counter(map(tuple, np.sort(d, 1).tolist())).values())
    boundary = int(T.edge_is_boundary.sum())
    assert mult[2] + mult[1] == sum(mult.values()) and mult[1] == r * boundary
    und = len(set(map(tuple, np.sort(d, 1).tolist())))
    assert L.n_points - und + L.n_triangles == T.euler_characteristic
    for quads in (False, True):
        off, corners, face, local = L.polygons(quads)
        assert np.array_equal(L.local_sample[local], corners)
        if not quads:
            assert np.array_equal(corners, L.triangles.ravel())
        if L0.edges(quads) is None:  # triangulated quads at r = 1: not settled (documented)
            assert L.edges(quads) is None
            continue
        ev, ce = L.edges(quads)
        ev = np.asarray(ev, dtype=np.int64)
        nxt = np.arange(len(corners)) + 1
        nxt[off[1:] - 1] = off[:-1]
        a, b = corners, corners[nxt]
        key = np.minimum(a, b) * L.n_points + np.maximum(a, b)
        got = np.minimum(ev[:, 0], ev[:, 1]) * L.n_points + np.maximum(ev[:, 0], ev[:, 1])
        assert len(np.unique(got)) == len(got) and np.array_equal(np.sort(got), np.unique(key))
        assert np.array_equal(got[np.ravel(ce)], key)
        # the same numbering of the mesh edges' segments and of the per-face counts
        ev0 = np.asarray(L0.edges(quads)[0])
        assert len(ev0) == len(ev) and np.array_equal(ev0[:T.n_edges * r], ev[:T.n_edges * r])


def test_flip_arguments_are_checked():
    T = MeshTopology([[0, 1, 2], [0, 2, 3, 4]], 5)
    for bad in ([0, 0], [3, -1], [-2, -1], [0], [0.0, -1.0]):
        with pytest.raises(InvalidParameterError):
            Lattice(T, 3, flip=bad)
    assert Lattice(T, 3, flip=[2, -1]).flip.tolist() == [2, -1]


@pytest.mark.parametrize("name", ["tri_grid", "icosphere"])
def test_right_and_acute_meshes_are_unchanged(name):
    """No corner above the threshold (right triangles of a grid, an icosphere): the
    surface's lattice is the lattice of the topology alone, array for array."""
    v, f = (primitives.grid(3, 2, kind="tri") if name == "tri_grid"
            else primitives.icosphere(2))
    s = BlendingSurface(v, f)
    assert np.degrees(s.layouts.angles.max()) <= 90 + 1e-9
    for r in (2, 5):
        L, L0 = s.lattice(r), Lattice(s.topology, r)
        assert np.all(L.flip == -1)
        assert np.array_equal(s.tessellate(r)[1], L0.triangles)
        for q in (False, True):
            assert all(np.array_equal(a, b) for a, b in zip(L.polygons(q), L0.polygons(q)))
            assert all(np.array_equal(a, b) for a, b in zip(L.edges(q), L0.edges(q)))


def test_surface_flips_its_obtuse_triangles_only():
    """A tetrahedron-like closed mesh with one 150-degree corner: the surface's lattice
    flips that face only, at that corner; the output points are the unflipped ones."""
    X = np.array([[0, 0, 0], [2, 0, 0], [1, 0.27, 0], [1, 0.5, 1.0]], dtype=float)
    F = [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]]
    # (without the fairing of mesh.fairing, which changes this tetrahedron's surface: the
    # flip is measured on the surface it was designed on)
    s = BlendingSurface(X, F, fairness=FairnessRule(turn=180.0))
    ang = np.degrees(s.layouts.angles).reshape(4, 3)
    assert ang[0, 2] > FLIP_ANGLE and (np.delete(ang, 0, 0) < FLIP_ANGLE).all()
    L = s.lattice(4)
    assert L.flip.tolist() == [2, -1, -1, -1]
    P, tri, _ = s.tessellate(4)
    L0 = Lattice(s.topology, 4)
    assert not np.array_equal(tri, L0.triangles)
    assert np.array_equal(tri[L.triangle_face > 0], L0.triangles[L0.triangle_face > 0])
    # worst 3D angle of the flipped face's output triangles drops
    a_new = _angles(P[tri[L.triangle_face == 0]]).max()
    a_old = _angles(P[L0.triangles[L0.triangle_face == 0]]).max()
    assert a_new < a_old
