"""The cover by metric balls of the general construction (paper sections 2.3-2.5):
psi_i = b(d(x, x_i)/R_i), phi_i = b(d(x, x_i)/rho_i) (39), (40), (41).

Candidate search with per-point radii and ONE search tree: a point x lies in
B_d(x_j, R_j) iff, for the l_p norm d (radius r_j in tree coordinates, p >= 1),

    |z - z_j|_p^p + h_j^p < Rt^p,   h_j = (Rt^p - r_j^p)^(1/p),  Rt = max_j r_j,

with z = w * x: the centres lifted to R^(n+1) by the height h_j, queried at height
0 with the single radius Rt in a cKDTree (Minkowski p). This is exact for
Euclidean, l_p and l_1 (and their weighted forms) and returns exactly the balls
that contain x, however much the radii vary; l_inf and quasi-norm balls are
searched through their circumscribed l_2 balls and filtered by the exact
distance. So each query costs O(log N + number of balls containing it).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InvalidPointSetError
from ..inputs import radii
from .covers import padded_ball_query
from .radii import MARGIN, auto_R, check_extent, nearest_distances, validate_radii

__all__ = ["BallCover"]


def _masked(jet, valid, nu):
    out = [np.where(valid, jet[0], 0.0)]
    if nu >= 1:
        out.append(np.where(valid[..., None], jet[1], 0.0))
    if nu >= 2:
        out.append(np.where(valid[..., None, None], jet[2], 0.0))
    return out + [None] * (2 - nu)


class BallCover:
    """Balls B_d(x_i, R_i) (size functions psi) and B_d(x_i, rho_i) (non-degeneracy phi).

    points (N, n); metric: a :class:`~gerbs_core.scattered.metrics.Metric`; kernel;
    R, rho: None (automatic, :mod:`gerbs_core.scattered.radii`), a scalar or (N,);
    tree: the cKDTree of the points (reused for the neighbour searches).
    Attributes: ``R``, ``rho`` (N,), ``certified`` (the automatic R provably covers
    the convex hull by the balls of radius MARGIN R_i = 0.9 R_i, see
    :func:`~gerbs_core.scattered.radii.auto_R`), ``max_gauge`` (every point of the hull
    has a ball with :meth:`~.metrics.Metric.gauge` <= max_gauge, so psi >= b(max_gauge);
    0.9 for a norm; inf without a certificate), ``disjoint_phi`` (rho_i + rho_j <=
    d(x_i, x_j): (34) holds, (35) applies).
    """

    def __init__(self, points, metric, kernel, R=None, rho=None, tree=None):
        self.points, self.metric, self.kernel = points, metric, kernel
        N = points.shape[0]
        p = getattr(metric.base, "p", 1.0)
        if N > 1 and p > 2.8:       # (|w y|^p: a narrower range than check_points')
            check_extent(metric.tree_coords(points), power=p,
                         what=f" for the l_p metric with p = {p:g}")
        self.nearest = nearest_distances(points, metric, tree)
        if R is None:
            if N < 2:
                raise InvalidPointSetError("points: cover='balls' needs R when N < 2")
            self.R, self.certified = auto_R(points, metric, tree=tree)
        else:
            self.R = radii("R", R, N)
            self.certified = False
        self.max_gauge = (metric.certified_gauge(MARGIN, metric.base_radius(self.R))
                          if self.certified else np.inf)
        if rho is None:
            bad = np.flatnonzero(~(self.nearest > 0))
            if bad.size:        # (the automatic radii: the points' fault, not rho's)
                raise InvalidPointSetError("points: numerically coincident in the metric "
                                           "(nearest distance 0) at indices", bad)
            self.rho = np.minimum(0.5 * self.nearest, self.R)
            self.disjoint_phi = True
        else:
            self.rho = radii("rho", rho, N)
            self.disjoint_phi = bool(np.all(self.rho <= 0.5 * self.nearest))
        validate_radii(self.rho, self.R, self.nearest)
        self._build_search()
        # balls per query on a sample (the data points, where overlaps peak): for
        # sizing query blocks before their candidates are known
        sample = points[:: max(1, N // 2000)]
        self.k_estimate = int((self.candidates(sample) >= 0).sum(axis=1).max())

    def search_bytes_per_query(self):
        """Working bytes of :meth:`candidates` per query row (upper bound: the k-NN
        doubling ends at k < 2 K + 16; the exact filter holds (K, n) offsets)."""
        n = self.points.shape[1]
        k = 2 * (2 * self.k_estimate + 16)
        return 8 * (4 * k + 3 * k * (n + 1)) + 64

    def _build_search(self):
        m = self.metric
        r, p = m.search_radius(m.base_radius(self.R))
        self._p = float(p)
        self._Rt = float(r.max())
        h = np.maximum(self._Rt ** self._p - r ** self._p, 0.0) ** (1.0 / self._p)
        z = np.concatenate([m.tree_coords(self.points), h[:, None]], axis=1)
        self._tree = cKDTree(z)

    def candidates(self, x):
        """Indices (M, K) of the balls B_d(x_j, R_j) containing x, -1 = empty slot,
        sorted by index within each row (the order (29) multiplies in)."""
        M = x.shape[0]
        z = np.concatenate([self.metric.tree_coords(x), np.zeros((M, 1))], axis=1)
        idx = padded_ball_query(self._tree, z, self._Rt * (1 + 1e-9), p=self._p)
        j = np.maximum(idx, 0)
        inside = (idx >= 0) & (self.metric.norm(x[:, None, :] - self.points[j]) < self.R[j])
        key = np.where(inside, idx, np.iinfo(np.int64).max)
        key.sort(axis=1)
        width = max(int(inside.sum(axis=1).max()) if M else 0, 1)
        key = key[:, :width]
        return np.where(key == np.iinfo(np.int64).max, -1, key)

    def well_inside(self, x, idx, margin=MARGIN):
        """Rows of x (M, n) with a candidate of ``idx`` (M, K) whose gauge is <= margin:
        inside the ball's core, where psi >= b(margin)."""
        valid = idx >= 0
        j = np.maximum(idx, 0)
        t = self.metric.gauge(x[:, None, :] - self.points[j], self.R[j])
        return (valid & (t <= margin)).any(axis=1)

    def jets(self, x, idx, nu, want_phi):
        """psi and (if ``want_phi``) phi jets (M, K, ...) of the candidates ``idx``."""
        valid = idx >= 0
        j = np.maximum(idx, 0)
        y = x[:, None, :] - self.points[j]
        psi = _masked(self.metric.bump_jet(y, self.R[j], self.kernel, nu), valid, nu)
        phi = None
        if want_phi:
            phi = _masked(self.metric.bump_jet(y, self.rho[j], self.kernel, nu), valid, nu)
        return psi, phi
