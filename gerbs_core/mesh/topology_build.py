"""The construction of :class:`~gerbs_core.mesh.topology.MeshTopology`: vectorized steps
from CSR faces to half-edges, edges and ordered vertex stars, each raising the
:class:`~gerbs_core.errors.InvalidMeshError` of the problem it detects (the tags and
their order are listed in :mod:`gerbs_core.mesh.topology`). O(C log C) for C corners.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidMeshError

__all__ = ["edge_error", "check_indices", "check_faces", "face_cycles", "mesh_edges",
           "vertex_stars"]


def edge_error(problem, what, pairs, faces):
    """The InvalidMeshError `problem` naming edges (vertex pairs (K, 2)) and their faces."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    shown = ", ".join(f"({a}, {b})" for a, b in pairs[:10].tolist())
    more = f" ... ({len(pairs)} edges in all)" if len(pairs) > 10 else ""
    faces = np.unique(np.asarray(faces, dtype=np.int64))
    err = InvalidMeshError(problem, f"{problem}: edges {shown}{more} {what} (faces "
                           f"{', '.join(map(str, faces[:20].tolist()))}); vertices",
                           np.unique(pairs), "vertex")
    err.edges = [tuple(p) for p in pairs.tolist()]
    err.faces = faces.tolist()
    return err


def check_indices(flat, cface, V: int) -> None:
    """index_out_of_range, then unused_vertex if there are more vertices than corners
    (before anything allocates O(V) memory: V may be huge)."""
    C = len(flat)
    bad = (flat < 0) | (flat >= V)
    if bad.any():
        raise InvalidMeshError("index_out_of_range", f"index_out_of_range: vertex indices "
                               f"{np.unique(flat[bad])[:10].tolist()} are outside [0, {V - 1}]"
                               f" in faces", np.unique(cface[bad]), "face")
    if V > C:
        unused = np.setdiff1d(np.arange(min(V, C + 1000)), flat)
        raise InvalidMeshError("unused_vertex", f"unused_vertex: {V} vertices but only {C} "
                               f"face corners; vertices in no face", unused, "vertex")


def check_faces(sizes, offsets, flat, cface) -> None:
    """degenerate_face, repeated_index, duplicate_face."""
    F, C = len(sizes), len(flat)
    # sort (face, vertex) pairs: repeated vertices inside a face become neighbours
    order = np.lexsort((flat, cface))
    sv = flat[order]
    rep = np.zeros(C, dtype=bool)
    rep[1:] = (sv[1:] == sv[:-1]) & (cface[1:] == cface[:-1])
    distinct = sizes - np.bincount(cface[rep], minlength=F)
    if (distinct < 3).any():
        raise InvalidMeshError("degenerate_face", "degenerate_face: fewer than 3 distinct "
                               "vertices in faces", np.flatnonzero(distinct < 3), "face")
    if rep.any():
        raise InvalidMeshError("repeated_index", "repeated_index: a vertex occurs twice in "
                               "faces", np.unique(cface[rep]), "face")
    _check_duplicates(sizes, offsets, sv)


def _check_duplicates(sizes, offsets, sorted_vertices) -> None:
    """Faces with the same vertex set (in any order) -> duplicate_face."""
    dups = []
    for k in np.unique(sizes):
        fk = np.flatnonzero(sizes == k)
        if len(fk) < 2:
            continue
        rows = sorted_vertices[offsets[fk][:, None] + np.arange(k)]
        o = np.lexsort(rows.T[::-1])
        eq = (rows[o[1:]] == rows[o[:-1]]).all(axis=1)
        if eq.any():
            dups.append(fk[o[1:][eq]])
            dups.append(fk[o[:-1][eq]])
    if dups:
        raise InvalidMeshError("duplicate_face", "duplicate_face: faces with the same "
                               "vertices", np.unique(np.concatenate(dups)), "face")


def face_cycles(offsets):
    """(next (C,), prev (C,)): the successor and predecessor of each corner in its face."""
    C = int(offsets[-1])
    nxt = np.arange(1, C + 1, dtype=np.int64)
    nxt[offsets[1:] - 1] = offsets[:-1]
    prv = np.empty(C, dtype=np.int64)
    prv[nxt] = np.arange(C, dtype=np.int64)
    return nxt, prv


def mesh_edges(flat, nxt, cface, V: int):
    """(halfedge_edge (C,), edge_halfedges (E, 2), twin (C,), edges (E, 2)) of the
    half-edges c -> next(c); raises non_manifold_edge, inconsistent_orientation.

    Edges are sorted by (low, high) vertex; a boundary edge keeps its one half-edge
    first, an inner edge the lower-numbered one."""
    C = len(flat)
    a, b = flat, flat[nxt]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    ukey = lo * V + hi
    eorder = np.argsort(ukey, kind="stable")
    sk = ukey[eorder]
    first = np.ones(C, dtype=bool)
    first[1:] = sk[1:] != sk[:-1]
    starts = np.flatnonzero(first)
    counts = np.diff(np.append(starts, C))
    if (counts > 2).any():
        bad_e = starts[counts > 2]
        grp = np.repeat(counts > 2, counts)
        raise edge_error("non_manifold_edge", "are shared by more than two faces",
                         np.stack([lo[eorder[bad_e]], hi[eorder[bad_e]]], 1),
                         cface[eorder[grp]])
    E = len(starts)
    he_edge = np.empty(C, dtype=np.int64)
    he_edge[eorder] = np.repeat(np.arange(E), counts)
    e_he = np.full((E, 2), -1, dtype=np.int64)
    e_he[:, 0] = eorder[starts]
    two = counts == 2
    e_he[two, 1] = eorder[starts[two] + 1]
    h0, h1 = e_he[two, 0], e_he[two, 1]
    same = a[h0] == a[h1]
    if same.any():
        raise edge_error("inconsistent_orientation", "are traversed in the same direction "
                         "by both their faces (flipped face orientation or non-orientable "
                         "surface)", np.stack([lo[h0[same]], hi[h0[same]]], 1),
                         np.concatenate([cface[h0[same]], cface[h1[same]]]))
    twin = np.full(C, -1, dtype=np.int64)
    twin[h0], twin[h1] = h1, h0
    edges = np.stack([lo[e_he[:, 0]], hi[e_he[:, 0]]], 1)
    return he_edge, e_he, twin, edges


def vertex_stars(flat, prv, twin, used, V: int):
    """(star_offsets (V+1,), star_corners (C,), vertex_is_boundary (V,)): the corners
    around each vertex counter-clockwise; raises non_manifold_vertex (bow-ties).

    Rotating counter-clockwise about v crosses the incoming half-edge (p -> v) of the
    current corner, so succ(c) = twin(prev(c)). Open fans start at the corner whose
    outgoing half-edge has no twin.
    """
    C = len(flat)
    succ = np.where(twin[prv] >= 0, twin[prv], -1)
    offsets = np.zeros(V + 1, dtype=np.int64)
    np.cumsum(used, out=offsets[1:])
    by_v = np.argsort(flat, kind="stable")  # corners grouped by vertex
    start = np.full(V, -1, dtype=np.int64)
    has = used > 0
    start[has] = by_v[offsets[:-1][has]]
    bnd_out = np.flatnonzero(twin < 0)  # corners whose outgoing half-edge is boundary
    nb = np.bincount(flat[bnd_out], minlength=V)
    start[flat[bnd_out]] = bnd_out
    bad = nb > 1  # two open fans at one vertex
    out = np.full(C, -1, dtype=np.int64)
    verts = np.flatnonzero(has)
    cur_v = start[verts]
    k = 0
    while verts.size:
        out[offsets[verts] + k] = cur_v
        cur_v = succ[cur_v]
        k += 1
        # stop at the end of an open fan, on closing the cycle, or at the corner count
        keep = (cur_v >= 0) & (cur_v != start[verts]) & (k < used[verts])
        done = verts[~keep]
        walked = np.full(done.shape, k)
        bad[done[walked < used[done]]] = True  # more corners than one fan holds
        verts, cur_v = verts[keep], cur_v[keep]
    if bad.any():
        raise InvalidMeshError("non_manifold_vertex", "non_manifold_vertex: the faces at "
                               "these vertices form more than one fan (bow-tie)",
                               np.flatnonzero(bad), "vertex")
    return offsets, out, nb > 0
