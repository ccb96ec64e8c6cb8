"""The self-crossing warning (gerbs_core.mesh.self_crossing): a surface that passes
through itself where its cage does not (a modelling session, 2026-12-07: a mug and a
table came out with their walls through each other, with no word)."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives
from gerbs_core.mesh import BlendingSurface
from gerbs_core.mesh.self_crossing import crossing_pairs


def cup(inset=0.12, depth=1.75, n=16):
    """A modeller's cup: a Cylinder (radius 1, z in [-1, 1]) whose top face is inset and
    extruded down by `depth`: outer wall, rim, inner wall (one row of quads each), the
    floor and the bottom n-gons. (V, 3), faces (outward)."""
    a = 2 * np.pi * np.arange(n) / n
    ring = np.stack([np.cos(a), np.sin(a)], axis=1)
    rings = [(1.0, -1.0), (1.0, 1.0), (1.0 - inset, 1.0), (1.0 - inset, 1.0 - depth)]
    V = np.concatenate([np.column_stack([r * ring, np.full(n, z)]) for r, z in rings])
    F = []
    for k in range(3):        # outer wall, rim, inner wall: ring k to ring k + 1
        for i in range(n):
            j = (i + 1) % n
            F.append((k * n + i, k * n + j, (k + 1) * n + j, (k + 1) * n + i))
    F.append(tuple(range(3 * n, 4 * n)))                  # the floor, facing up
    F.append(tuple(reversed(range(n))))                   # the bottom, facing down
    return V, F


def test_crossing_triangles_and_the_controls():
    X = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0],                 # in z = 0
                  [0.5, 0.5, -1], [0.5, 0.5, 1], [1.5, 1.5, 0.2],  # through it
                  [0, 0, 1], [2, 0, 1], [0, 2, 1],                 # parallel, apart
                  [0, 0, 0.0], [-1, 0, 0], [0, -1, 0]], float)     # touching at a point
    T = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8], [9, 10, 11]])
    assert crossing_pairs(X, T).tolist() == [[0, 1]]
    # sharing an index is never a crossing (neighbours); moved off the plane: none
    assert crossing_pairs(X, np.array([[0, 1, 2], [0, 4, 5]])).tolist() == []
    Y = X.copy()
    Y[3:6, 2] += 2.0
    assert crossing_pairs(Y, T).tolist() == []


def test_a_cup_whose_floor_meets_its_bottom_warns_naming_them():
    V, F = cup()
    s = BlendingSurface(V, F)
    (w,) = [w for w in s.warnings if w.tag == "self_crossing"]
    n = 16
    walls_and_caps = set(range(n)) | set(range(2 * n, 3 * n)) | {3 * n, 3 * n + 1}
    assert w.element == "face" and w.indices and set(w.indices) <= walls_and_caps, w.indices
    assert {3 * n, 3 * n + 1} <= set(w.indices)           # the floor through the bottom
    assert "passes through itself" in w.message and "loop cuts" in w.message
    # the control: a thick-walled cup of the same recipe does not cross, and does not warn
    thick = BlendingSurface(*cup(inset=0.4, depth=1.0))
    assert "self_crossing" not in [w.tag for w in thick.warnings]


def test_a_cage_that_crosses_itself_is_not_blamed_on_the_surface():
    """Suzanne's eyes pass through her head in the cage; her surface does too (410 pairs at
    r = 4), as drawn: no warning."""
    X, faces = primitives.suzanne()
    s = BlendingSurface(X, faces)
    assert "self_crossing" not in [w.tag for w in s.warnings]
    from gerbs_core.mesh.self_crossing import surface_crossings
    P, T, _ = s.tessellate(4)
    assert len(crossing_pairs(P, T)) > 100                    # the crossings are there
    lat = s.lattice(4)
    assert len(surface_crossings(s.topology, s.vertices, P, T, lat.triangle_face)) == 0


def test_a_seam_whose_copies_differ_by_rounding_is_one_place():
    """A review (2026-12-07): Suzanne's right half detached along x = 0 (an open seam, its
    vertices duplicated) warned on 42 faces along the seam once the copies differed by
    1e-9, where the repair itself calls them one seam (its tolerance, SEAM_RTOL)."""
    X, F = primitives.suzanne()
    V, dup, F2 = list(X), {}, []
    for f in F:
        if X[list(f)].mean(axis=0)[0] > 0:
            F2.append(tuple(dup.setdefault(i, len(V) + len(dup)) for i in f))
        else:
            F2.append(tuple(f))
    V = np.concatenate([X, X[sorted(dup, key=dup.get)]])
    for offset in (0.0, 1e-9):
        W = V.copy()
        W[len(X):] += offset
        tags = [w.tag for w in BlendingSurface(W, F2).warnings]
        assert "open_seam" in tags and "self_crossing" not in tags, (offset, tags)
