"""A certificate that metric balls cover the convex hull of the points with a margin.

Claim certified (Definition 11 with a floor): every x in every simplex of a
simplicialization of the hull (the Delaunay one) has a point x_j with
d(x, x_j) <= margin * R_j (distances and radii in the base norm of the metric,
:meth:`~gerbs_core.scattered.metrics.Metric.base_radius`), so psi_j(x) >= b(margin)
(radial bumps (39)) or b(margin)^m (tensor bumps (41), m factors).

Proof step, for a (sub-)simplex S with centroid c and r = max_k d(c, v_k): the
ball B_d(c, r) of a norm is convex and contains the vertices, so S lies in it;
if d(c, x_j) + r <= margin R_j for some j, the triangle inequality puts S in
B_d(x_j, margin R_j). Simplices not certified by one of the ``k`` points
nearest to c are bisected at their longest edge (both halves are checked again)
while they are large against the balls near them (r >= ``split`` R_j); a smaller
piece (and any piece after ``max_depth`` levels, or beyond a work cap) enlarges the
radius of its best candidate just enough to certify it (a relative growth of
about ``split`` at most). Radii only grow, so the
pieces certified earlier stay certified: the returned radii certify the whole
hull. Only the pieces near gaps of the point set (hull slivers) are bisected,
so the work is O(simplices) plus a small multiple for the boundary.

Needs a convex ball (a norm, or d/(1+d) of one): not for quasi-norms.
"""
from __future__ import annotations

import numpy as np

__all__ = ["certify_cover"]


def _bisect(S):
    """Split each simplex (W, n+1, n) at the midpoint of its longest edge -> (2W, n+1, n)."""
    W, m, _ = S.shape
    a, b = np.triu_indices(m, 1)
    L = np.sum((S[:, a] - S[:, b]) ** 2, axis=-1)
    e = np.argmax(L, axis=1)
    ia, ib = a[e], b[e]
    rows = np.arange(W)
    mid = 0.5 * (S[rows, ia] + S[rows, ib])
    left, right = S.copy(), S.copy()
    left[rows, ib] = mid
    right[rows, ia] = mid
    return np.concatenate([left, right])


def certify_cover(points, simplices, Rb, norm, tree, margin=0.9, k=8, split=0.5, max_depth=None,
                  max_pieces=None):
    """Radii Rb' >= Rb (base norm) whose balls of radius margin * Rb' cover every simplex.

    points (N, n); simplices (T, n+1) int; Rb (N,) radii in the base norm ``norm``
    (a :class:`~gerbs_core.scattered.metrics.Metric` with ``convex``); tree: a cKDTree
    of ``points`` (candidates by Euclidean distance; any candidate may certify).
    Returns (Rb' (N,), number of radii enlarged). Exact up to rounding (1e-12 slack).
    """
    N, n = points.shape
    R = np.array(Rb, dtype=float, copy=True)
    k = min(k, N)
    max_depth = 4 * n if max_depth is None else int(max_depth)
    max_pieces = 8 * len(simplices) + 100_000 if max_pieces is None else int(max_pieces)
    enlarged = np.zeros(N, bool)
    # first the simplices' own vertices as candidates (no search): most pass
    S = points[simplices]
    c = S.mean(axis=1)
    r = norm.norm(S - c[:, None, :]).max(axis=1)
    own = (margin * R[simplices] - norm.norm(S - c[:, None, :])).max(axis=1) >= r * (1 + 1e-12)
    S = S[~own]
    done = int(own.sum())
    for depth in range(max_depth + 1):
        if not len(S):
            break
        c = S.mean(axis=1)
        r = norm.norm(S - c[:, None, :]).max(axis=1)
        _, j = tree.query(c, k=k)
        j = j.reshape(len(c), k)
        slack = margin * R[j] - norm.norm(points[j] - c[:, None, :])
        best = np.argmax(slack, axis=1)
        ok = slack[np.arange(len(c)), best] >= r * (1 + 1e-12)
        done += int(ok.sum())
        S, c, r, j, best, slack = S[~ok], c[~ok], r[~ok], j[~ok], best[~ok], slack[~ok]
        if not len(S):
            break
        # a piece already small against the local balls gains little from bisection:
        # enlarge the candidate that needs the least growth (then it is certified)
        grow = r < split * R[j[np.arange(len(S)), best]]
        if depth == max_depth or done + 2 * len(S) > max_pieces:
            grow[:] = True
        if grow.any():
            jb = j[grow, best[grow]]
            need = (norm.norm(points[jb] - c[grow]) + r[grow]) * (1 + 1e-9) / margin
            np.maximum.at(R, jb, need)
            enlarged[jb] = True
        S = _bisect(S[~grow])
    return R, int(enlarged.sum())
