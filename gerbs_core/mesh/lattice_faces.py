"""The output mesh of a sample lattice: its faces and edges (:meth:`Lattice.polygons`,
:meth:`Lattice.edges` of :mod:`gerbs_core.mesh.lattice`).

Output faces are quads in quad faces (with ``quads``) and the lattice triangles
elsewhere. The edges are numbered from the lattice structure, without hashing the
output's half-edges: the r segments of every mesh edge first, then the edges inside
the faces, face-size class by class (:attr:`Lattice.size_classes`), face by face.
"""
from __future__ import annotations

import numpy as np

from .arrays import read_only as _ro
from .arrays import unique_rows
from .lattice_templates import face_counts, template_edges, template_faces, variant_rows

__all__ = ["corner_counts", "polygon_table", "output_edges"]


def _offsets(counts) -> np.ndarray:
    off = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=off[1:])
    return off


def corner_counts(lat, quads: bool) -> np.ndarray:
    """(F,) output corners of each face: 4 r^2 for quads with `quads`, else 3 x its
    triangles."""
    sizes, r = lat.topology.face_sizes, lat.resolution
    return np.where((sizes == 4) & quads, 4 * r * r, 3 * face_counts(sizes, r)[1])


def polygon_table(lat, quads: bool):
    """(offsets, corners, face, local) of :meth:`Lattice.polygons` (read-only int64)."""
    tp, r = lat.topology, lat.resolution
    coff = _offsets(corner_counts(lat, quads))
    fcount = np.where((tp.face_sizes == 4) & quads, r * r, face_counts(tp.face_sizes, r)[1])
    foff = _offsets(fcount)
    corners = np.empty(int(coff[-1]), dtype=np.int64)
    local = np.empty(int(coff[-1]), dtype=np.int64)
    sizes = np.empty(int(foff[-1]), dtype=np.int64)
    for fk0, G0, _, n in lat.size_classes:
        for rows, v in variant_rows(lat.flip[fk0]):
            fk, G, tf = fk0[rows], G0[rows], template_faces(n, r, quads, v)
            dest = (coff[fk][:, None] + np.arange(tf.size)).ravel()
            corners[dest] = G[:, tf.ravel()].ravel()
            local[dest] = (lat.local_offsets[fk][:, None] + tf.ravel()).ravel()
            sizes[(foff[fk][:, None] + np.arange(len(tf))).ravel()] = tf.shape[1]
    face = np.repeat(np.arange(tp.n_faces, dtype=np.int64), fcount)
    return _ro(_offsets(sizes)), _ro(corners), _ro(face), _ro(local)


def _inner_counts(lat, quads: bool) -> list[int]:
    """Edges inside the faces of each size class (all its faces)."""
    return [int((template_edges(n, lat.resolution, quads)[2] < 0).sum()) * len(fk)
            for fk, _, _, n in lat.size_classes]


def _mesh_edge_segments(tp, r: int, ev: np.ndarray) -> None:
    """Write the r segments of every mesh edge e into ``ev[e*r + j]`` (segment j from
    ``edges[e,0]``)."""
    V, E, i32 = tp.n_vertices, tp.n_edges, np.int32
    S = np.empty((E, r + 1), dtype=i32)  # samples along each mesh edge
    S[:, 0], S[:, r] = tp.edges[:, 0], tp.edges[:, 1]
    S[:, 1:r] = V + np.arange(E * (r - 1), dtype=i32).reshape(E, r - 1)
    ev[:E * r, 0] = S[:, :-1].ravel()
    ev[:E * r, 1] = S[:, 1:].ravel()


def _class_edges(lat, part, cnt: int, base: int, quads: bool, ev: np.ndarray):
    """Edges of one size class: writes its ``cnt`` inner edges into ``ev[base:]`` and
    returns (first inner edge of each face (nf,), edge of every corner of its template
    faces (nf, corners)). Faces of another triangulation (``lat.flip``) have as many
    inner edges (any triangulation of the same points and sides has), numbered in the
    same place, between other points."""
    tp, r, i32 = lat.topology, lat.resolution, np.int32
    fo, fv = tp.face_offsets, tp.face_vertices
    fk0, G0, _, n = part
    nf = len(fk0)
    ni = cnt // max(nf, 1)
    ev_c = ev[base:base + cnt].reshape(nf, 2 * ni)
    for rows, v in variant_rows(lat.flip[fk0]):
        fk, G = fk0[rows], G0[rows]
        tedge, face_edge, side, seg = template_edges(n, r, quads, v)
        ids = np.empty((len(fk), len(tedge)), dtype=i32)
        ids[:, :ni] = base + ni * np.arange(nf, dtype=i32)[rows][:, None] + np.arange(ni,
                                                                                  dtype=i32)
        h = fo[fk][:, None] + side[ni:][None, :]  # half-edge of the side
        e = tp.halfedge_edge[h]
        m = seg[ni:][None, :]
        ids[:, ni:] = e * r + np.where(fv[h] == tp.edges[e, 0], m, r - 1 - m)
        got = np.take(ids, face_edge.ravel(), axis=1)
        if isinstance(rows, slice):  # the whole class first (variant_rows)
            np.take(G.astype(i32), tedge[:ni].ravel(), axis=1, mode="clip", out=ev_c)
            ce = got
        else:
            ev_c[rows] = G[:, tedge[:ni].ravel()]
            ce[rows] = got
    return base + ni * np.arange(nf), ce


def _merge_repeats(lat, quads: bool, ev, ce, inner_of):
    """(ev, ce) with the repeated inner edges of the faces around interior vertices of
    valence <= 2 merged (the only places an inner edge can be another face's too)."""
    tp, r, i32 = lat.topology, lat.resolution, np.int32
    weak = np.flatnonzero(~np.asarray(tp.vertex_is_boundary, dtype=bool)
                          & (np.diff(tp.star_offsets) <= 2))
    if not len(weak):
        return ev, ce
    so, sc = tp.star_offsets, tp.star_corners
    faces = np.unique(tp.corner_face[np.concatenate(
        [sc[so[w]:so[w + 1]] for w in weak.tolist()])])
    nin = {n: int((template_edges(n, r, quads)[2] < 0).sum()) for _, _, _, n in lat.size_classes}
    cand = np.concatenate([inner_of[f] + np.arange(nin[int(tp.face_sizes[f])])
                           for f in faces.tolist()])
    pair = np.sort(ev[cand], axis=1)
    first, inv = unique_rows(pair)
    if len(first) < len(cand):
        remap = np.arange(len(ev), dtype=i32)
        remap[cand] = cand[first[inv.ravel()]]
        keep = remap == np.arange(len(ev))
        remap = (np.cumsum(keep, dtype=i32) - 1)[remap]
        ev, ce = ev[keep], remap[ce]
    return ev, ce


def output_edges(lat, quads: bool):
    """(edge_verts, corner_edges) of :meth:`Lattice.edges`, or None where the lattice
    structure alone does not settle them."""
    tp, r = lat.topology, lat.resolution
    E = tp.n_edges
    if (r == 1 and np.any(tp.face_sizes == 4) and not quads) or lat.n_points >= 2 ** 31 - 1:
        return None
    n_in = _inner_counts(lat, quads)
    ev = np.empty((E * r + sum(n_in), 2), dtype=np.int32)
    _mesh_edge_segments(tp, r, ev)
    coff = _offsets(corner_counts(lat, quads))
    ce = np.empty(int(coff[-1]), dtype=np.int32)
    inner_of = np.empty(tp.n_faces + 1, dtype=np.int64)  # first inner edge id per face
    inner_of[-1] = len(ev)
    base = E * r
    for part, cnt in zip(lat.size_classes, n_in):
        fk = part[0]
        inner_of[fk], got = _class_edges(lat, part, cnt, base, quads, ev)
        base += cnt
        if len(lat.size_classes) == 1:
            ce[:] = got.ravel()
        else:
            ce[(coff[fk][:, None] + np.arange(got.shape[1])).ravel()] = got.ravel()
    ev, ce = _merge_repeats(lat, quads, ev, ce, inner_of)
    return ev, (ce if quads else ce.reshape(-1, 3))
