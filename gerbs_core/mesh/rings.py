"""The data of the local fits: the vertices around each vertex, in its chart.

Ring 1 of vertex v: the other corners of v's star faces, at their exact chart
positions zeta_v(x) (:mod:`gerbs_core.mesh.charts`). Ring 2: the corners of the
faces across the far edges of the star faces, each such face unfolded
isometrically into the plane of the star face it borders (the faces of a mesh
glue isometrically along shared edges, :mod:`gerbs_core.mesh.layout`), then
angle-scaled like the chart, continuously about that star face's middle angle.

On a curved mesh an unfolding depends on the path: a ring-2 vertex reached
through several star faces gets a different position from each (the opposite
corner of a cube, reached through three faces, lands at three points 120 degrees
apart). Each placement is a datum of its own (equal placements, to round-off,
count once), so the data do not depend on the order of the faces or on where a
star starts: the fits, and hence the surface, are independent of the numbering.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DataRings", "data_rings"]


@dataclass(frozen=True)
class DataRings:
    """Per vertex (CSR by ``offsets`` (V+1,)): data vertex ``ids`` (N,), their chart
    positions ``y`` (N, 2) and ``ring`` (N,) 1 or 2; within a vertex ordered by
    (ring, id). ``h`` (V,): mean chart distance of the ring-1 data (the fit scale)."""

    offsets: np.ndarray
    ids: np.ndarray
    y: np.ndarray
    ring: np.ndarray
    h: np.ndarray


def _chart_points(charts, corner, z, tref):
    """Unfolded complex points z of corner's chart -> chart points, the angle taken
    continuously about tref (elementwise)."""
    th = tref + np.angle(z * np.exp(-1j * tref))
    r = np.abs(z)
    s = charts.scale[charts.corner_vertex[corner]]
    return np.stack([r * np.cos(s * th), r * np.sin(s * th)], axis=-1)


def _ring1(topo, charts, corners2d):
    """(v, q, y) for every star corner c of v and every other corner of c's face."""
    sizes, off, cf = topo.face_sizes, topo.face_offsets, topo.corner_face
    vs, qs, ys = [], [], []
    for n in np.unique(sizes).tolist():
        cs = np.flatnonzero(sizes[cf] == n)
        k = cs - off[cf[cs]]
        idx = off[cf[cs]][:, None] + (k[:, None] + 1 + np.arange(n - 1)) % n
        r, th = charts.unfolded(np.broadcast_to(cs[:, None], idx.shape), corners2d[idx])
        s = charts.scale[charts.corner_vertex[cs]][:, None]
        ys.append(np.stack([r * np.cos(s * th), r * np.sin(s * th)], -1).reshape(-1, 2))
        vs.append(np.repeat(charts.corner_vertex[cs], n - 1))
        qs.append(topo.face_vertices[idx].ravel())
    return np.concatenate(vs), np.concatenate(qs), np.concatenate(ys)


def _star_placements(topo, charts, corners2d):
    """The star faces of every vertex as placements (c, face, z): z (K, n_max) complex, the
    face's corners unfolded in the chart frame of star corner c (padding 0)."""
    sizes, off, cf = topo.face_sizes, topo.face_offsets, topo.corner_face
    nmax = int(sizes.max())
    c = np.arange(topo.n_corners)
    z = np.zeros((len(c), nmax), dtype=complex)
    for n in np.unique(sizes).tolist():
        cs = np.flatnonzero(sizes[cf] == n)
        idx = off[cf[cs]][:, None] + np.arange(n)
        r, th = charts.unfolded(np.broadcast_to(cs[:, None], idx.shape), corners2d[idx])
        z[cs, :n] = r * np.exp(1j * th)
    return c, cf[c], z


def _unfold_next(topo, corners2d, c, face, z, placed):
    """Faces across the edges of the placed faces (c, face, z), unfolded isometrically into
    the same frames; skips faces in ``placed`` (keys v * F + face). Returns (c, face, z)."""
    sizes, off, cf = topo.face_sizes, topo.face_offsets, topo.corner_face
    nxt, twin, V_of = topo.corner_next, topo.halfedge_twin, topo.face_vertices
    zc = corners2d[:, 0] + 1j * corners2d[:, 1]
    n_f = sizes[face]
    k = np.repeat(np.arange(len(face)), n_f)
    i = np.arange(len(k)) - np.repeat(np.cumsum(n_f) - n_f, n_f)
    h = off[face[k]] + i                                  # half-edge i of the placed face
    t = twin[h]
    ok = t >= 0
    k, i, h, t = k[ok], i[ok], h[ok], t[ok]
    g = cf[t]
    v = V_of[c[k]]
    fresh = ~np.isin(v * topo.n_faces + g, placed)
    k, i, h, t, g = k[fresh], i[fresh], h[fresh], t[fresh], g[fresh]
    za = z[k, (i + 1) % n_f[k]]
    zb = z[k, i]
    rot = (zb - za) / (zc[nxt[t]] - zc[t])
    rot /= np.abs(rot)
    out = np.zeros((len(g), z.shape[1]), dtype=complex)
    for n in np.unique(sizes[g]).tolist():
        sel = np.flatnonzero(sizes[g] == n)
        gc = off[g[sel]][:, None] + np.arange(n)
        out[sel, :n] = za[sel, None] + (zc[gc] - zc[t[sel], None]) * rot[sel, None]
    return c[k], g, out


def _corner_points(topo, charts, c, face, z):
    """(v, q, y): every corner of the placed faces in v's chart (angle about c's middle)."""
    sizes, off = topo.face_sizes, topo.face_offsets
    n_f = sizes[face]
    k = np.repeat(np.arange(len(face)), n_f)
    j = np.arange(len(k)) - np.repeat(np.cumsum(n_f) - n_f, n_f)
    tref = charts.theta0[c[k]] + 0.5 * charts.alpha[c[k]]
    y = _chart_points(charts, c[k], z[k, j], tref)
    return charts.corner_vertex[c[k]], topo.face_vertices[off[face[k]] + j], y


def _distinct(v, q, y, scale):
    """The distinct (v, q, y) triples, sorted by (v, q, angle of y): placements closer than
    1e-9 of the star's scale count once (the two faces of a spoke give one neighbour up to
    round-off), compared with the previous kept placement of the same (v, q) so the result
    does not depend on the input order."""
    ang = np.arctan2(y[:, 1], y[:, 0])
    # (v, q) as one integer key: the order of lexsort((ang, q, v)) with one key less
    span = int(q.max()) + 1 if len(q) else 1
    order = np.lexsort((ang, v.astype(np.int64) * span + q))
    v, q, y = v[order], q[order], y[order]
    tol = 1e-9 * scale[v]
    keep = np.ones(len(v), dtype=bool)
    same = (v[1:] == v[:-1]) & (q[1:] == q[:-1])
    close = same & (np.linalg.norm(y[1:] - y[:-1], axis=1) <= tol[1:])
    # runs of close placements: keep the first of each run (a run is one placement)
    keep[1:] = ~close
    return v[keep], q[keep], y[keep]


def data_rings(topo, charts, corners2d, layers: int = 2, min_data: int = 7) -> DataRings:
    """Ring-1 and ring-2 data of every vertex (see the module docstring); vertices with
    fewer than ``min_data`` data in rings 1-2 (boundary corners) also get ring 3."""
    V, F = topo.n_vertices, topo.n_faces
    # the scale of each star, for _distinct: its longest layout edge
    edge = np.linalg.norm(corners2d[topo.corner_next] - corners2d, axis=1)
    longest = np.zeros(F)
    np.maximum.at(longest, topo.corner_face, edge)
    scale = np.zeros(V)
    np.maximum.at(scale, topo.face_vertices, longest[topo.corner_face])
    v1, q1, y1 = _distinct(*_ring1(topo, charts, corners2d), scale)
    keep = q1 != v1
    parts = [(v1[keep], q1[keep], y1[keep], 1)]
    c, face, z = _star_placements(topo, charts, corners2d)
    placed = charts.corner_vertex[c] * F + face
    for ring in range(2, 4):
        if ring > layers and ring == 2:
            break
        if ring == 3:   # only where rings 1-2 hold too few data: unfold only their faces
            have = np.bincount(np.concatenate([p[0] for p in parts]), minlength=V)
            sel = have[charts.corner_vertex[c]] < min_data
            c, face, z = c[sel], face[sel], z[sel]
        c, face, z = _unfold_next(topo, corners2d, c, face, z, placed)
        if not len(c):
            break
        placed = np.concatenate([placed, charts.corner_vertex[c] * F + face])
        v, q, y = _distinct(*_corner_points(topo, charts, c, face, z), scale)
        known = np.zeros(len(v), dtype=bool)
        for pv, pq, _, _ in parts:
            known |= np.isin(v * V + q, pv * V + pq)
        known |= q == v
        parts.append((v[~known], q[~known], y[~known], ring))
    v = np.concatenate([p[0] for p in parts])
    q = np.concatenate([p[1] for p in parts])
    y = np.concatenate([p[2] for p in parts])
    ring = np.concatenate([np.full(len(p[0]), p[3]) for p in parts])
    span = int(ring.max()) + 1 if len(ring) else 1
    order = np.lexsort((q, v.astype(np.int64) * span + ring))     # by (v, ring), then q
    v, q, y, ring = v[order], q[order], y[order], ring[order]
    offsets = np.zeros(V + 1, dtype=np.int64)
    np.cumsum(np.bincount(v, minlength=V), out=offsets[1:])
    d = np.hypot(y[:, 0], y[:, 1])
    one = ring == 1
    n1 = np.bincount(v[one], minlength=V)
    h = np.bincount(v[one], d[one], minlength=V) / np.maximum(n1, 1)
    return DataRings(offsets, q, y, ring, h)
