"""Manifold sheets of :func:`gerbs_core.mesh.repair.repair_mesh`: which faces are glued
along which edges, their orientation, and one vertex per fan.

Half-edges are indexed like corners (half-edge c runs from ``flat[c]`` to
``flat[next(c)]``); ``partner (C,)`` is the half-edge glued to c, or -1 (a boundary).

* An edge of two faces glues them. An edge of k >= 3 faces is split into sheets by
  :func:`pair_edge`: among the matchings of its faces into pairs that traverse the
  edge in opposite directions (consistent orientation) and do not cross each other
  around the edge, the one with the most pairs, then the smallest largest bend
  |pi - opening angle|, then the smallest total bend, then the most convex pairs
  (a pair's faces bound the wedge behind their normals: two solids that share an
  edge stay two closed solids). Unpaired faces have the edge as a boundary.
* :func:`orient` flips faces so that every glued pair is consistent, the fewer faces of
  each connected piece; where no orientation exists (a Moebius band) glued pairs are
  cut until one does.
* :func:`fans`: the corners at a vertex joined through glued edges form its fans; each
  fan gets its own copy of the vertex.
"""
from __future__ import annotations

import math

import numpy as np

from .validation import corner_successors

__all__ = ["glue", "orient", "fans", "pair_edge"]

EXHAUSTIVE_MAX = 10  # edges of more faces are paired greedily (neighbours first)


def _prev(sizes):
    nxt = corner_successors(sizes)
    prv = np.empty_like(nxt)
    prv[nxt] = np.arange(len(nxt))
    return nxt, prv


def _matchings(ang, sign, lo, hi):
    """Every non-crossing partial matching of the faces lo..hi-1 (sorted by angle) whose
    pairs are consistent, as lists of (i, j); small k only (Motzkin many)."""
    if hi - lo < 2:
        return [[]]
    out = [m for m in _matchings(ang, sign, lo + 1, hi)]  # lo unpaired
    for j in range(lo + 1, hi):
        if sign[lo] != sign[j]:
            for left in _matchings(ang, sign, lo + 1, j):
                for right in _matchings(ang, sign, j + 1, hi):
                    out.append([(lo, j)] + left + right)
    return out


def _score(pairs, ang, sign):
    bends = [abs(math.pi - (ang[j] - ang[i])) for i, j in pairs]
    convex = sum(1 for i, j in pairs if (sign[i] < 0) == (ang[j] - ang[i] < math.pi))
    return (-len(pairs), max(bends, default=0.0), sum(bends), -convex)


def pair_edge(ang, sign):
    """Pairs (i, j) of the faces at one edge (see the module docstring).

    ang (k,) angle of each face about the edge (radians, any origin); sign (k,) +1 where
    the face traverses the edge forwards, -1 backwards. Deterministic (ties: lower indices)."""
    ang = np.asarray(ang, dtype=np.float64) % (2 * math.pi)
    order = np.lexsort((np.arange(len(ang)), ang))
    a, s = ang[order].tolist(), np.asarray(sign)[order].tolist()
    if len(a) <= EXHAUSTIVE_MAX:
        best = min(_matchings(a, s, 0, len(a)), key=lambda m: _score(m, a, s))
    else:
        best, left = [], list(range(len(a)))
        while True:
            cand = [(left[t], left[(t + 1) % len(left)]) for t in range(len(left))
                    if s[left[t]] != s[left[(t + 1) % len(left)]]] if len(left) > 1 else []
            if not cand:
                break
            i, j = min(cand, key=lambda p: _score([tuple(sorted(p))], a, s))
            best.append(tuple(sorted((i, j))))
            left = [t for t in left if t not in (i, j)]
    return [(int(order[i]), int(order[j])) for i, j in best]


def _edge_frame(x, lo, hi):
    d = x[hi] - x[lo]
    n = np.linalg.norm(d)
    d = d / n if n > 0 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(d, np.eye(3)[int(np.argmin(np.abs(d)))])
    e1 /= np.linalg.norm(e1)
    return d, e1, np.cross(d, e1)


def glue(x, sizes, flat):
    """(partner (C,), the non-manifold edges as (lo, hi) pairs (N, 2), the faces on them)."""
    C = len(flat)
    V = int(flat.max()) + 1
    nxt, prv = _prev(sizes)
    a, b = flat, flat[nxt]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.argsort(lo * V + hi, kind="stable")
    key = (lo * V + hi)[order]
    start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    count = np.diff(np.r_[start, C])
    partner = np.full(C, -1, dtype=np.int64)
    two = start[count == 2]
    partner[order[two]], partner[order[two + 1]] = order[two + 1], order[two]
    many = start[count > 2]
    cface = np.repeat(np.arange(len(sizes)), sizes)
    for s0, k in zip(many.tolist(), count[count > 2].tolist()):
        hs = order[s0:s0 + k]
        d, e1, e2 = _edge_frame(x, lo[hs[0]], hi[hs[0]])
        # direction into each face: its corners beside the edge, less their part along it
        w = 0.5 * (x[flat[nxt[nxt[hs]]]] + x[flat[prv[hs]]]) - x[lo[hs[0]]]
        w -= np.outer(w @ d, d)
        ang = np.arctan2(w @ e2, w @ e1)
        sign = np.where(a[hs] == lo[hs], 1, -1)
        for i, j in pair_edge(ang, sign):
            partner[hs[i]], partner[hs[j]] = hs[j], hs[i]
    bad = np.stack([lo[order[many]], hi[order[many]]], 1)
    faces = np.unique(cface[order[np.repeat(count > 2, count)]])
    return partner, bad, faces


def orient(sizes, flat, partner):
    """(flip (F,) bool, cut (M,) half-edges whose glue was cut): flips making every glued
    pair traverse its edge in opposite directions, the smaller part of each piece."""
    nxt, _ = _prev(sizes)
    F = len(sizes)
    cface = np.repeat(np.arange(F), sizes)
    g = np.flatnonzero(partner > np.arange(len(flat)))  # each glued pair once
    same = flat[g] == flat[partner[g]]
    flip = np.zeros(F, dtype=bool)
    if not same.any():
        return flip, np.zeros(0, dtype=np.int64)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    f1, f2 = cface[g], cface[partner[g]]
    graph = coo_matrix((np.ones(len(g)), (f1, f2)), shape=(F, F)).tocsr()
    n, label = connected_components(graph, directed=False)
    parity = np.zeros(F, dtype=np.int64)
    flips_of = {(min(p, q), max(p, q)): int(sm) for p, q, sm in zip(f1, f2, same)}
    pieces = np.unique(label[f1[same]])
    for piece in pieces.tolist():
        root = int(np.flatnonzero(label == piece)[0])
        seq, pred = breadth_first_order(graph, root, directed=False)
        for f in seq[1:].tolist():
            p = int(pred[f])
            parity[f] = parity[p] ^ flips_of[(min(f, p), max(f, p))]
        members = label == piece
        if parity[members].sum() * 2 > members.sum():
            parity[members] ^= 1
    bad = (same.astype(np.int64) ^ parity[f1] ^ parity[f2]) != 0
    return parity.astype(bool), np.concatenate([g[bad], partner[g[bad]]])


def flip_faces(sizes, flat, partner, flip):
    """Reverse the faces marked in `flip` keeping their first corner; partner remapped."""
    if not flip.any():
        return flat, partner
    offsets = np.r_[0, np.cumsum(sizes)]
    cface = np.repeat(np.arange(len(sizes)), sizes)
    pos = np.arange(len(flat)) - offsets[cface]
    n = sizes[cface]
    f = flip[cface]
    src = np.where(f, offsets[cface] + (-pos) % n, np.arange(len(flat)))  # new corner <- old
    new_flat = flat[src]
    # old half-edge at position k becomes the new half-edge at n - 1 - k (reversed)
    moved = np.where(f, offsets[cface] + (n - 1 - pos) % n, np.arange(len(flat)))
    new_partner = np.full_like(partner, -1)
    glued = partner >= 0
    new_partner[moved[glued]] = moved[partner[glued]]
    return new_flat, new_partner


def fans(sizes, flat, partner):
    """(copy (C,) fan label of every corner, unique per (vertex, fan))."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    C = len(flat)
    nxt, _ = _prev(sizes)
    h = np.flatnonzero(partner >= 0)
    # half-edge c (v -> w) glued to t (w -> v): the corner of c at v and next(t) share a fan
    graph = coo_matrix((np.ones(len(h)), (h, nxt[partner[h]])), shape=(C, C))
    _, label = connected_components(graph, directed=False)
    return label


def conflicts(sizes, flat_new, partner):
    """Half-edges sharing end points (in the new vertex numbering) without being glued
    to each other: they would make MeshTopology see a non-manifold edge."""
    C = len(flat_new)
    nxt, _ = _prev(sizes)
    V = int(flat_new.max()) + 1
    a, b = flat_new, flat_new[nxt]
    key = np.minimum(a, b) * V + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    k = key[order]
    start = np.flatnonzero(np.r_[True, k[1:] != k[:-1]])
    count = np.diff(np.r_[start, C])
    ok2 = (count == 2) & (partner[order[start]] == order[np.minimum(start + 1, C - 1)])
    bad = (count > 2) | ((count == 2) & ~ok2)
    return [order[s:s + c] for s, c in zip(start[bad].tolist(), count[bad].tolist())]
