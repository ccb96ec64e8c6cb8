"""Face-level repairs of :func:`gerbs_core.mesh.repair.repair_mesh`: welding, repeated
indices, degenerate, duplicate and zero-area faces.

Faces travel as CSR arrays: ``sizes (F,)`` corner counts, ``flat (C,)`` the vertex of
every corner, ``origin (F,)`` the input face each face comes from. Every function
returns new arrays (the caller's are never modified) and appends its findings to
``notes``, a list of ``(tag, input indices, element, detail)`` tuples that
:mod:`gerbs_core.mesh.repair` turns into warnings.
"""
from __future__ import annotations

from collections import defaultdict

import numpy as np

from .validation import chain_faces, corner_successors

__all__ = ["weld_map", "clean_faces", "merge_zero_area"]

COLLINEAR_RTOL = 1e-8  # corners within 1e-8 of the longest edge from one line are collinear


def unique_edges(sizes, flat, V):
    """(E, 2) the edges (lo, hi) of CSR faces (corner counts ``sizes``, vertices ``flat``),
    each once, ascending; none between a vertex and itself."""
    nxt = corner_successors(sizes)
    lo, hi = np.minimum(flat, flat[nxt]), np.maximum(flat, flat[nxt])
    keys = np.unique(lo[lo != hi] * V + hi[lo != hi])
    return np.stack([keys // V, keys % V], 1)


def weld_map(x, sizes, flat, merge_distance, rtol, notes):
    """(V,) the vertex every vertex is welded to (itself if none): the lowest index of
    its cluster, whose position the cluster takes (as Blender's Merge by Distance).

    Clusters join (transitively) the end points of zero-length edges (length <= rtol
    times the median edge length: the validation's rule) and, if ``merge_distance``
    is not None, all vertices within that distance of each other (0: coincident ones).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    V = len(x)
    e = unique_edges(sizes, flat, V)
    pairs = [np.zeros((0, 2), dtype=np.int64)]
    if len(e):
        length = np.linalg.norm(x[e[:, 1]] - x[e[:, 0]], axis=1)
        short = e[length <= rtol * float(np.median(length))]
        if len(short):
            notes.append(("zero_length_edge", np.unique(short), "vertex", short))
            pairs.append(short)
    if merge_distance is not None:
        from scipy.spatial import cKDTree
        close = cKDTree(x).query_pairs(float(merge_distance), output_type="ndarray")
        pairs.append(close.astype(np.int64).reshape(-1, 2))
    p = np.concatenate(pairs)
    if not len(p):
        return np.arange(V)
    graph = coo_matrix((np.ones(len(p)), (p[:, 0], p[:, 1])), shape=(V, V))
    _, label = connected_components(graph, directed=False)
    lowest = np.full(label.max() + 1, V)
    np.minimum.at(lowest, label, np.arange(V))
    rep = lowest[label]
    if merge_distance is not None and np.any(rep != np.arange(V)):
        gone = np.flatnonzero(rep != np.arange(V))
        notes.append(("merged_vertices", gone, "vertex", np.stack([gone, rep[gone]], 1)))
    return rep


def _face_ids(sizes):
    return np.repeat(np.arange(len(sizes)), sizes)


def _has_repeats(sizes, flat):
    """(F,) bool: faces visiting some vertex twice."""
    cf = _face_ids(sizes)
    order = np.lexsort((flat, cf))
    sv, sf = flat[order], cf[order]
    rep = np.zeros(len(flat), dtype=bool)
    rep[1:] = (sv[1:] == sv[:-1]) & (sf[1:] == sf[:-1])
    out = np.zeros(len(sizes), dtype=bool)
    out[sf[rep]] = True
    return out


def _split_loops(face):
    """A polygon that revisits vertices, cut at every revisit into simple loops (in
    order, orientation kept): (a, b, c, a, d, e) -> (a, b, c), (a, d, e)."""
    stack, loops = [], []
    for v in face:
        if v in stack:
            k = stack.index(v)
            loops.append(stack[k:])
            del stack[k + 1:]
        else:
            stack.append(v)
    return loops + [stack]


def _from_lists(faces, origin):
    sizes = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
    flat = np.fromiter((v for f in faces for v in f), dtype=np.int64, count=int(sizes.sum()))
    return sizes, flat, np.asarray(origin, dtype=np.int64)


def clean_faces(sizes, flat, origin, input_sizes, input_repeats, notes):
    """Collapse repeated consecutive corners, cut faces that revisit a vertex into simple
    loops, drop faces of fewer than 3 vertices and all but the first of faces with the
    same vertex set."""
    prv = np.empty_like(flat)
    prv[corner_successors(sizes)] = np.arange(len(flat))
    keep = flat != flat[prv]
    cf = _face_ids(sizes)
    sizes, flat = np.bincount(cf[keep], minlength=len(sizes)), flat[keep]
    pinched = _has_repeats(sizes, flat)
    if pinched.any():
        offsets = np.r_[0, np.cumsum(sizes)]
        faces, orig = [], []
        for f in range(len(sizes)):
            loops = _split_loops(flat[offsets[f]:offsets[f + 1]].tolist()) if pinched[f] \
                else [flat[offsets[f]:offsets[f + 1]]]
            faces += loops
            orig += [origin[f]] * len(loops)
        sizes, flat, origin = _from_lists(faces, orig)
    if input_repeats.any():
        notes.append(("repeated_index", np.flatnonzero(input_repeats), "face", None))
    small = sizes < 3
    if small.any():
        lost = np.setdiff1d(origin[small], origin[~small])
        edge = lost[input_sizes[lost] == 2]
        if len(edge):
            notes.append(("loose_edge", edge, "face", None))
        if len(lost) > len(edge):
            notes.append(("degenerate_face", np.setdiff1d(lost, edge), "face", "few"))
        sizes, flat, origin = _select(sizes, flat, origin, ~small)
    return _drop_duplicates(sizes, flat, origin, notes)


def _select(sizes, flat, origin, keep):
    return sizes[keep], flat[np.repeat(keep, sizes)], origin[keep]


def _drop_duplicates(sizes, flat, origin, notes):
    offsets = np.r_[0, np.cumsum(sizes)]
    dup = np.zeros(len(sizes), dtype=bool)
    for k in np.unique(sizes).tolist():
        fk = np.flatnonzero(sizes == k)
        rows = np.sort(flat[offsets[fk][:, None] + np.arange(k)], axis=1)
        _, first = np.unique(rows, axis=0, return_index=True)
        dup[fk] = True
        dup[fk[first]] = False  # np.unique keeps the first occurrence of every row
    if dup.any():
        notes.append(("duplicate_face", np.unique(origin[dup]), "face", None))
        sizes, flat, origin = _select(sizes, flat, origin, ~dup)
    return sizes, flat, origin


def _collinear(x, face):
    p = x[face]
    d = np.linalg.norm(p[:, None] - p[None], axis=2)
    i, j = np.unravel_index(np.argmax(d), d.shape)
    if d[i, j] == 0:
        return False
    u = (p[j] - p[i]) / d[i, j]
    off = (p - p[i]) - np.outer((p - p[i]) @ u, u)
    return bool(np.linalg.norm(off, axis=1).max() <= COLLINEAR_RTOL * d[i, j])


def _absorb(host, face, k):
    """`host` with the edge face[k] - face[k+1] replaced by the rest of `face`'s boundary
    (orientation of `host` kept), or None if the result would revisit a vertex."""
    u, v = face[k], face[(k + 1) % len(face)]
    path = face[k + 1:] + face[:k + 1]  # v ... u
    n = len(host)
    for i in range(n):
        a, b = host[i], host[(i + 1) % n]
        if (a, b) in ((v, u), (u, v)):
            inner = path[1:-1] if (a, b) == (v, u) else path[-2:0:-1]
            new = host[:i + 1] + inner + host[i + 1:]
            return new if len(set(new)) == len(new) else None
    return None


def merge_zero_area(x, sizes, flat, origin, flat_mask, notes):
    """Zero-area faces (``flat_mask`` (F,): :func:`gerbs_core.mesh.validation.flat_faces`,
    which the caller needs too): collinear ones are
    merged into the face across their longest edge (the neighbour's boundary then runs
    along their other edges, so the surface closes over them); those with no single
    neighbour there, or self-cancelling ones (zero vector area, corners not on a line),
    are dropped, and the surface is bounded by their neighbours."""
    if not flat_mask.any():
        return sizes, flat, origin
    chain = chain_faces(x, sizes, flat)  # collinear to the positions' rounding
    offsets = np.r_[0, np.cumsum(sizes)]
    faces = [flat[offsets[f]:offsets[f + 1]].tolist() for f in range(len(sizes))]
    on_edge = defaultdict(set)
    for f, vs in enumerate(faces):
        for a, b in zip(vs, vs[1:] + vs[:1]):
            on_edge[(min(a, b), max(a, b))].add(f)
    alive = np.ones(len(faces), dtype=bool)
    merged, dropped = [], []
    for d in np.flatnonzero(flat_mask).tolist():
        vs = faces[d]
        length = np.linalg.norm(x[vs] - x[vs[1:] + vs[:1]], axis=1)
        k = int(np.argmax(length))
        u, v = vs[k], vs[(k + 1) % len(vs)]
        hosts = on_edge[(min(u, v), max(u, v))] - {d}
        new = _absorb(faces[next(iter(hosts))], vs, k) \
            if len(hosts) == 1 and (chain[d] or _collinear(x, vs)) else None
        for a, b in zip(vs, vs[1:] + vs[:1]):
            on_edge[(min(a, b), max(a, b))].discard(d)
        alive[d] = False
        if new is None:
            dropped.append(origin[d])
            continue
        h = hosts.pop()
        on_edge[(min(u, v), max(u, v))].discard(h)
        for a, b in zip(new, new[1:] + new[:1]):
            on_edge[(min(a, b), max(a, b))].add(h)
        faces[h] = new
        merged.append(origin[d])
    if merged:
        notes.append(("zero_area_face", np.unique(merged), "face", None))
    if dropped:
        notes.append(("degenerate_face", np.unique(dropped), "face", "area"))
    keep = np.flatnonzero(alive)
    return _from_lists([faces[f] for f in keep], origin[keep])


def input_repeats(sizes, flat):
    """(F,) bool: input faces that name a vertex twice (reported as ``repeated_index``)."""
    return _has_repeats(sizes, flat)
