"""Concave faces are split into convex ones (repair stage 3b, gerbs_core.mesh.repair_concave).

Found by a test with messy meshes: every face is laid out as a convex polygon, so the
surface of a flat star-shaped 12-gon folded over itself (36 of 192 output triangles
reversed at r = 4), an L-shaped 12-gon likewise (6)."""
import math

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from gerbs_core import BlendingSurface
from gerbs_core.mesh.repair_concave import LIMIT, _turns, concave_faces, convex_pieces

from .test_mesh_repair import _check_surface, _tags


def _star(n=12, inner=0.4):
    t = 2 * np.pi * np.arange(n) / n
    r = np.where(np.arange(n) % 2 == 0, 1.0, inner)
    return np.stack([r * np.cos(t), r * np.sin(t), np.zeros(n)], axis=1)


L12 = np.array([(0, 0), (1, 0), (2, 0), (2, 0.5), (2, 1), (1, 1), (1, 1.5), (1, 2), (0.5, 2),
                (0, 2), (0, 1.5), (0, 1)], dtype=float)


def _reversed(s, r=4):
    P, T, _ = s.tessellate(r)
    c = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])[:, 2]
    return int((c * np.sign(np.median(c)) < 0).sum()), P


@pytest.mark.parametrize("name", ["star", "L"])
def test_a_flat_concave_ngon_does_not_fold(name):
    X = _star() if name == "star" else np.c_[L12, np.zeros(12)]
    # rotated out of the xy-plane: the test is in the face's own plane
    R = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))[0]
    s = BlendingSurface(X @ R.T, [tuple(range(12))])
    w = _tags(s)
    assert list(w) == ["concave_face"] and w["concave_face"].indices == (0,)
    assert s.topology.n_faces > 1 and (s.face_map == 0).all()
    flipped, P = _reversed(BlendingSurface(X, [tuple(range(12))]))
    assert flipped == 0
    assert np.abs((P - X[0]) @ np.array([0, 0, 1.0])).max() <= 1e-12  # in its plane
    _check_surface(s, X @ R.T)


def test_concave_pentagons_are_split_beyond_ten_degrees_and_quads_are_kept():
    """A flat dart pentagon (reflex corner at vertex 1, a straight corner at 3): kept at 5
    degrees, cut at 40 and 90. Dart quads are kept whatever their angle (a deformation
    makes quads concave, and a split would change the topology from frame to frame): at
    90 degrees 57 of 512 output triangles are reversed at r = 8 (a known limit)."""
    for degrees, split in ((5, False), (40, True), (90, True)):
        h = math.tan(math.radians(degrees / 2))
        X = np.array([(0, 0, 0), (1, h, 0), (2, 0, 0), (2, 0.75, 0), (1, 1.5, 0)], dtype=float)
        s = BlendingSurface(X, [(0, 1, 2, 3, 4)])
        assert (s.topology.n_faces > 1) == split
        assert bool(s.warnings) == split
        if split:
            assert _reversed(s, 8)[0] == 0
    quad = np.array([(0, 0, 0), (1, 1.0, 0), (2, 0, 0), (1, 1.5, 0)], dtype=float)
    s = BlendingSurface(quad, [(0, 1, 2, 3)])
    assert s.topology.n_faces == 1 and not s.warnings
    assert _reversed(s, 8)[0] == 57


def test_mildly_concave_faces_of_real_meshes_are_kept(monkeypatch):
    """Suzanne has two quads turning back by about 1 degree: below the angle, so they
    would be kept even if quads were split (bench_shape's real meshes are untouched)."""
    from pathlib import Path
    from gerbs_core.datasets.obj import read_obj
    from gerbs_core.mesh import repair_concave

    V, F = read_obj(str(Path(__file__).resolve().parents[2] / "examples" / "suzanne.obj"))[:2]
    sizes = np.array([len(f) for f in F])
    flat = np.concatenate([np.asarray(f) for f in F])
    monkeypatch.setattr(repair_concave, "MIN_CORNERS", 3)
    assert not concave_faces(np.asarray(V, float), sizes, flat).any()
    monkeypatch.setattr(repair_concave, "REFLEX", math.radians(0.5))
    assert concave_faces(np.asarray(V, float), sizes, flat).sum() == 2


def _area(p):
    return 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.2, 1.0), min_size=4, max_size=24), st.floats(0, 6.28))
# (a cut once left a near-straight triangle it could not cut: the face came back whole)
@example([1.0, 0.296875, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0.65625, 1, 0.22265625, 1.0], 0.0)
def test_convex_pieces_cover_a_star_shaped_polygon_with_convex_polygons(radii, phase):
    n = len(radii)
    t = phase + 2 * np.pi * np.arange(n) / n
    p = np.stack([np.array(radii) * np.cos(t), np.array(radii) * np.sin(t)], axis=1)
    pieces = convex_pieces(p)
    assert pieces and sorted(set(i for q in pieces for i in q)) == list(range(n))
    for q in pieces:
        assert len(q) >= 3 and (_turns(p[q]) >= -1e-9).all()  # convex, counter-clockwise
    assert sum(_area(p[q]) for q in pieces) == pytest.approx(_area(p), rel=1e-12)
    assert len(pieces) <= max(1, n - 2)  # at most a triangulation's count
    if not (math.pi - _turns(p) > LIMIT).any():  # every corner below 179 degrees: kept whole
        assert len(pieces) == 1


def test_the_split_of_a_symmetric_face_does_not_flip_under_rounding():
    """The L's cuts tie; a 1e-12 move of its reflex corner once changed the pieces (121 ->
    137 output points at r = 4). Ties within 1e-6 radians go to the first corner."""
    p0 = convex_pieces(L12)
    assert len(p0) > 1
    for t in (1e-14, 1e-12, 1e-10, 1e-8):
        for k in (5, 6, 11):
            M = L12.copy()
            M[k] += t
            assert convex_pieces(M) == p0


def test_a_chord_that_is_already_an_edge_is_not_cut():
    """Found by a review: an L hexagon whose best cut (0, 3) is also an edge of a triangle
    standing on it; cutting there made an edge of three faces."""
    from gerbs_core.mesh.repair import repair_mesh

    L = np.array([(0, 0, 0), (2, 0, 0), (2, 1, 0), (1, 1, 0), (1, 2, 0), (0, 2, 0)], float)
    assert [0, 3] in [sorted(set(a) & set(b)) for a in convex_pieces(L[:, :2])
                      for b in convex_pieces(L[:, :2]) if a != b]
    X = np.vstack([L, [(0.5, 0.5, 1.0)]])
    r = repair_mesh(X, [tuple(range(6)), (3, 0, 6)])
    tags = [w.tag for w in r.warnings]
    assert "concave_face" in tags and "non_manifold_edge" not in tags
    T = r.topology
    assert T.n_faces > 2 and int((T.edge_faces[:, 1] >= 0).sum() + len(T.edge_faces)) > 0


def test_a_small_face_far_from_the_origin_is_cut_as_at_the_origin():
    """Found by a review: the faces' normals were summed from absolute coordinates, 63
    degrees off for a 1 cm face at 5e6, so its concavity was missed."""
    p = _star()[:, :2] * 0.01
    pieces = convex_pieces(p)
    for offset in (5e5, 5e6):
        X = np.c_[p + offset, np.full(12, offset)]
        s = BlendingSurface(X, [tuple(range(12))])
        assert [w.tag for w in s.warnings] == ["concave_face"]
        assert len(s.topology.face_sizes) == len(pieces)


def test_a_finely_segmented_concave_curve_is_split():
    """Found by a test with concave n-gons: a half annulus whose inner arc turns back by
    7.5 degrees at each of its 24 corners (180 in all) was not split (no corner beyond 10
    degrees) and folded, 230 of 800 output triangles reversed at r = 4."""
    seg = 24
    outer = [(np.cos(t), np.sin(t), 0) for t in np.linspace(-np.pi / 2, np.pi / 2, seg + 1)]
    inner = [(0.55 * np.cos(t), 0.55 * np.sin(t), 0) for t in np.linspace(np.pi / 2, -np.pi / 2, seg + 1)]
    X = np.array(outer + inner)
    s = BlendingSurface(X, [tuple(range(len(X)))])
    assert [w.tag for w in s.warnings] == ["concave_face"]
    assert _reversed(s)[0] == 0


@pytest.mark.parametrize("points,inner", [(6, 0.4), (32, 0.8), (100, 0.8)])
def test_gears_and_stars_lose_their_teeth_first(points, inner):
    """Found by a test with concave n-gons: a gear (a Circle filled as one n-gon, every
    other vertex scaled) was cut across into long slivers and folded (64 corners: 162 of
    1,120 output triangles reversed; 200 corners: 440 of 3,488 and 3.4x the cage's
    extent). Its teeth are cut off first: one triangle a tooth and the inner polygon."""
    n = 2 * points
    p = _star(n, inner)
    pieces = convex_pieces(p[:, :2])
    assert sorted(len(q) for q in pieces) == [3] * points + [points]
    s = BlendingSurface(p, [tuple(range(n))])
    flipped, P = _reversed(s)
    assert flipped == 0 and np.abs(np.ptp(P, axis=0)[:2] / np.ptp(p, axis=0)[:2] - 1).max() < 1e-9
