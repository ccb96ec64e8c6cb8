"""Face layouts: cyclic polygons with the faces' rest edge lengths."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.errors import InvalidMeshError
from gerbs_core.mesh.layout import cyclic_polygon, face_layouts
from gerbs_core.mesh.topology import MeshTopology


def _check_cyclic(pts, lengths):
    n = len(lengths)
    el = np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1)
    assert np.allclose(el, lengths, rtol=0, atol=1e-13 * lengths.max())
    a, b, c = pts[0], pts[1], pts[2]
    A = 2 * np.array([b - a, c - a])
    o = np.linalg.solve(A, [b @ b - a @ a, c @ c - a @ a])
    R = np.linalg.norm(pts - o, axis=1)
    assert np.ptp(R) <= 1e-13 * R.max()  # concyclic
    nxt, prv = np.roll(pts, -1, 0) - pts, np.roll(pts, 1, 0) - pts
    cross = nxt[:, 0] * prv[:, 1] - nxt[:, 1] * prv[:, 0]
    assert np.all(cross > 0)  # strictly convex, counter-clockwise
    assert np.allclose(pts[0], 0) and abs(pts[1, 1]) < 1e-15 and n == len(pts)


@pytest.mark.parametrize("lengths", [
    [1, 1, 1, 1], [1, 1, 1, 1, 1], [1] * 8, [1, 2, 1.5, 1.1, 0.7],
    [3, 1, 1, 1.2],            # centre outside: longest edge dominates (non-centred)
    [2.9, 1, 1, 1],            # strongly non-centred
    [1.0, 1.0, 1.0, 1.9999],   # nearly flat, centred side
    [0.3, 2, 0.3, 2],          # rectangle-like
])
def test_cyclic_polygon_has_the_lengths_and_is_concyclic_convex(lengths):
    L = np.array(lengths, float)
    _check_cyclic(cyclic_polygon(L[None])[0], L)


def test_regular_polygons_have_regular_angles():
    for n in range(3, 9):
        pts = cyclic_polygon(np.ones((1, n)))[0]
        _check_cyclic(pts, np.ones(n))
        topo = MeshTopology([list(range(n))], n)
        t = 2 * np.pi * np.arange(n) / n
        sh = face_layouts(topo, np.stack([np.cos(t), np.sin(t), 0 * t], 1))
        assert np.allclose(sh.angles, np.pi * (n - 2) / n, atol=1e-14)


def test_triangles_exact_and_metric_lengths_from_positions():
    V, F = P.delaunay_patch(40, 1)
    topo = MeshTopology(F, len(V))
    sh = face_layouts(topo, V)
    # flat triangles are congruent to their 3D shapes: same corner angles
    fv, nx, pv = topo.face_vertices, topo.corner_next, topo.corner_prev
    a, b = V[fv[nx]] - V[fv], V[fv[pv]] - V[fv]
    ang = np.arccos(np.sum(a * b, 1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1))
    assert np.abs(sh.angles - ang).max() < 1e-12
    assert np.abs(sh.lengths - np.linalg.norm(V[fv[nx]] - V[fv], axis=1)).max() < 1e-15
    # angle sum of every triangle is pi, of every polygon (n-2) pi
    s = np.add.reduceat(sh.angles, topo.face_offsets[:-1])
    assert np.abs(s - np.pi).max() < 1e-13


def test_mixed_mesh_shared_edges_have_equal_lengths():
    V, F = P.mixed_mesh(bend=0.5)
    topo = MeshTopology(F, len(V))
    sh = face_layouts(topo, V)
    c = sh.corners
    L = np.linalg.norm(c[topo.corner_next] - c, axis=1)
    tw = topo.halfedge_twin
    ok = tw >= 0
    assert np.abs(L[ok] - L[tw[ok]]).max() < 1e-13
    s = np.add.reduceat(sh.angles, topo.face_offsets[:-1])
    assert np.abs(s - np.pi * (topo.face_sizes - 2)).max() < 1e-12


def test_bad_input():
    topo = MeshTopology([[0, 1, 2, 3]], 4)
    # an edge as long as the three others together: no convex polygon
    pos = np.array([[0, 0, 0], [3, 0, 0], [2, 0.0, 0], [1, 0, 0]], float)
    with pytest.raises(InvalidMeshError) as e:
        face_layouts(topo, pos)
    assert e.value.problem == "degenerate_face" and e.value.indices == (0,)
