"""The edges of a triangle mesh, found once by sorting its half-edges: the fairing's pairs of
adjacent output triangles and :func:`gerbs_core.testing.fairness.edge_adjacency` (the fold
and curvature yardsticks) read the same runs."""
from __future__ import annotations

import numpy as np

__all__ = ["edge_runs", "triangle_pairs"]


def edge_runs(triangles) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(order (3T,), start (E,), count (E,)) for triangles (T, 3) int.

    Half-edge h = k T + t runs from corner k to corner k + 1 (mod 3) of triangle t (every
    triangle's 01 first, then the 12s, then the 20s). ``order`` sorts the half-edges stably
    by their undirected edge (keyed by its lower, then higher corner); the E edges' runs in
    that order start at ``start`` and hold ``count`` half-edges (1: boundary, 2: interior,
    more: non-manifold)."""
    T = np.asarray(triangles, dtype=np.int64)
    nxt = T[:, [1, 2, 0]]
    n = int(T.max()) + 1 if len(T) else 0
    key = (np.minimum(T, nxt) * n + np.maximum(T, nxt)).T.ravel()
    order = np.argsort(key, kind="stable")
    k = key[order]
    new = np.ones(len(k), bool)
    new[1:] = k[1:] != k[:-1]
    start = np.flatnonzero(new)
    count = np.diff(np.append(start, len(k)))
    return order, start, count


def triangle_pairs(triangles) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) the two triangles (T, 3) of every edge shared by exactly two of them: pairs in
    the order of their edges' (lower, higher) corner, A the one whose edge comes first in
    the order (corners 01 of every triangle, then 12, then 20). Two triangles sharing more
    than one edge (a doubled triangle) make one pair per shared edge."""
    m = len(triangles)
    order, start, count = edge_runs(triangles)
    two = start[count == 2]
    return order[two] % m, order[two + 1] % m
