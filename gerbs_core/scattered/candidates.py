"""Which cover elements can be non-zero at a query point, for the star covers of
:class:`~gerbs_core.scattered.hermite.GERBSInterpolator` (ball covers search their own:
:meth:`~gerbs_core.scattered.balls.BallCover.candidates`).

Candidates are padded (M, K) int arrays, -1 an empty slot."""
from __future__ import annotations

import numpy as np

from .covers import padded_ball_query

__all__ = ["delaunay_candidates", "StarCandidates"]


def delaunay_candidates(tri, simplices, x):
    """The vertices (M, 3) of the Delaunay triangle containing each x (-1 outside the
    hull) and the star edge of each (index 3 t + k of corner k of triangle t)."""
    # small tolerance: points on the hull boundary belong to the domain
    simp = tri.find_simplex(x, tol=1e-12)
    ok = simp >= 0
    if ok.all():               # (every query inside the hull: gathers without the masks)
        return simplices[simp], 3 * simp[:, None] + np.arange(3)
    idx = np.where(ok[:, None], simplices[np.maximum(simp, 0)], -1)
    edge = np.where(ok[:, None], 3 * np.maximum(simp, 0)[:, None] + np.arange(3), -1)
    return idx, edge


class StarCandidates:
    """Stars whose support radius reaches x, for covers of star polygons (Voronoi,
    user polygons): typical stars through a KD-tree ball query with radius r = the
    99 % quantile of the support radii; the few larger ones (cells at the domain
    boundary) by a direct distance check, so the query stays local.

    points (N, n) the star centres, tree a cKDTree of them, support_radius (N,).
    """

    def __init__(self, points, tree, support_radius):
        self.points, self.tree, self.R = points, tree, support_radius
        self.r_typ = float(np.quantile(support_radius, 0.99))
        self.big = np.flatnonzero(support_radius > self.r_typ)

    def __call__(self, x):
        """Padded candidates (M, K), valid entries first, no all-empty column."""
        R = self.R
        idx = padded_ball_query(self.tree, x, self.r_typ * (1 + 1e-12))
        j = np.maximum(idx, 0)
        d = np.linalg.norm(x[:, None, :] - self.points[j], axis=-1)
        idx = np.where((idx >= 0) & (d < R[j]) & (R[j] <= self.r_typ), idx, -1)
        if self.big.size:
            db = np.linalg.norm(x[:, None, :] - self.points[self.big], axis=-1)
            idx = np.concatenate([idx, np.where(db < R[self.big], self.big, -1)], axis=1)
        o = np.argsort(idx < 0, axis=1, kind="stable")
        idx = np.take_along_axis(idx, o, 1)
        width = max(int((idx >= 0).sum(1).max()) if idx.size else 0, 1)
        return idx[:, :width]
