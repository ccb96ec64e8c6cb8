"""Vertex charts: unfolding, angle scaling, boundary rules, exact derivatives."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.errors import InvalidParameterError
from gerbs_core.mesh.charts import vertex_charts
from gerbs_core.mesh.cover import star_boundary
from gerbs_core.mesh.layout import face_layouts
from gerbs_core.mesh.topology import MeshTopology


def _charts(V, F, rule="keep"):
    topo = MeshTopology(F, len(V))
    sh = face_layouts(topo, V)
    ch = vertex_charts(topo, sh.corners, sh.angles, rule)
    return topo, sh, ch


MESHES = {"ico": P.icosphere(1), "uv": P.uv_sphere(8, 5), "mixed": P.mixed_mesh(bend=0.4),
          "tri": P.grid(3, 3, kind="tri"), "suzanne": P.suzanne()}


@pytest.mark.parametrize("name", sorted(MESHES))
def test_spokes_agree_from_both_faces_and_stars_close(name):
    V, F = MESHES[name]
    topo, sh, ch = _charts(V, F)
    fv, nx, tw = topo.face_vertices, topo.corner_next, topo.halfedge_twin
    # the spoke v -> next(c) seen from face of c and from the twin face (corner next(twin))
    c = np.flatnonzero(tw >= 0)
    c2 = nx[tw[c]]
    y1 = ch.to_chart(c, 0.6 * sh.corners[nx[c]] + 0.4 * sh.corners[c])[0]
    y2 = ch.to_chart(c2, 0.6 * sh.corners[topo.corner_prev[c2]] + 0.4 * sh.corners[c2])[0]
    assert np.abs(y1 - y2).max() < 1e-12 * np.abs(y1).max()
    # angle scaling: interior stars close (s * T = 2 pi)
    inner = ~topo.vertex_is_boundary
    assert np.abs(ch.scale[inner] * ch.span[inner] - 2 * np.pi).max() < 1e-13


def test_boundary_rules():
    V, F = P.mixed_mesh(bend=0.4)
    topo, sh, keep = _charts(V, F, "keep")
    _, _, straight = _charts(V, F, "straighten")
    b = topo.vertex_is_boundary
    small = b & (keep.span <= 1.5 * np.pi)
    assert small.any() and np.all(keep.scale[small] == 1.0)
    assert np.all(keep.scale[b] * keep.span[b] <= 1.5 * np.pi + 1e-12)
    assert np.abs(straight.scale[b] * straight.span[b] - np.pi).max() < 1e-13
    with pytest.raises(InvalidParameterError, match="boundary"):
        _charts(V, F, "round")


def test_flat_metric_keep_chart_is_isometric():
    V, F = P.delaunay_patch(40, 2)
    topo, sh, ch = _charts(V, F, "keep")
    rng = np.random.default_rng(0)
    for v in range(len(V)):
        star = topo.star_corners[topo.star_offsets[v]:topo.star_offsets[v + 1]]
        c = rng.choice(star, 6)
        f = topo.corner_face[c]
        w = rng.dirichlet(np.ones(3), 6)
        cs = topo.face_offsets[f][:, None] + np.arange(3)
        x2 = np.einsum("pk,pkd->pd", w, sh.corners[cs])
        X3 = np.einsum("pk,pkd->pd", w, V[topo.face_vertices[cs]])[:, :2]
        y = ch.to_chart(c, x2)[0]
        D = lambda a: np.linalg.norm(a[:, None] - a[None], axis=-1)  # noqa: E731
        assert np.abs(D(y) - D(X3)).max() < 1e-13
        dist = np.linalg.norm(X3 - V[v, :2], axis=1)
        assert np.abs(np.linalg.norm(y, axis=1) - dist).max() < 1e-13


def test_derivatives_match_finite_differences_and_inverse():
    V, F = P.mixed_mesh(bend=0.4)
    topo, sh, ch = _charts(V, F)
    c = np.arange(topo.n_corners)
    f = topo.corner_face[c]
    ctr = np.add.reduceat(sh.corners, topo.face_offsets[:-1], 0) / topo.face_sizes[:, None]
    x = 0.5 * ctr[f] + 0.5 * (0.7 * sh.corners[c] + 0.3 * sh.corners[topo.corner_next[c]])
    y, J, H = ch.to_chart(c, x, 2)
    h = 1e-5
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        yp, Jp = ch.to_chart(c, x + e, 1)
        ym, Jm = ch.to_chart(c, x - e, 1)
        assert np.abs((yp - ym) / (2 * h) - J[..., j]).max() < 1e-8
        assert np.abs((Jp - Jm) / (2 * h) - H[..., j]).max() < 1e-6
    for v in range(topo.n_vertices):
        star = topo.star_corners[topo.star_offsets[v]:topo.star_offsets[v + 1]]
        m = np.isin(c, star)
        c2, x2 = ch.from_chart(v, y[m], star)
        assert np.array_equal(c2, c[m]) and np.abs(x2 - x[m]).max() < 1e-13


def test_star_boundary_is_the_far_edges():
    V, F = P.uv_sphere(6, 4)
    topo, sh, ch = _charts(V, F)
    th, r = star_boundary(topo, ch, sh.corners, 0)  # north pole: 6 triangles
    assert len(th) == 7 and np.isclose(th[-1] - th[0], ch.span[0])
    assert np.allclose(r, np.linalg.norm(V[1] - V[0]))
    th, r = star_boundary(topo, ch, sh.corners, 8)  # a quad-band vertex (valence 4)
    assert len(th) == 4 * 2 + 1 and np.all(np.diff(th) > 0)
