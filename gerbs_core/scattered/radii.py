"""Point-set validation and the radii rho_i, R_i of the general construction.

Constraints (paper section 2.2, case (B), mesh-free Hermite interpolation):

* (16)  0 < rho_i <= min_{j != i} d(x_i, x_j)
* (17)  rho_i <= R_i < inf
* (13)  for ball covers Omega_i = B_d(x_i, R_i), max_{dOmega_i} d(x, x_i) = R_i holds.

Automatic choice:

* rho_i = 1/2 min_{j != i} d(x_i, x_j) (Remark 6), so the phi supports are
  disjoint, (34), and the simplified forms (35)/(36) apply;
* R_i = max_{j in Del(i)} d(x_i, x_j) / margin (margin = 0.9), the longest
  Delaunay edge at x_i. For a norm (convex balls) every point x of a Delaunay
  simplex T satisfies d(x, v) <= longest edge of T for each vertex v of T, so
  every vertex of T has psi_v(x) >= b(margin) > 0: the balls cover the convex
  hull with a guaranteed thickness (Definition 11). For n = 1 the neighbours are
  the adjacent points. If Qhull fails (degenerate sets in n >= 2) or n > 6,
  R_i = 2 x the distance to the (n+1)-th neighbour (no guarantee; check
  ``diagnostics.thickness``).

Nearest-neighbour searches use scipy.spatial.cKDTree (N log N).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree, Delaunay
from scipy.spatial import QhullError

from ..errors import InvalidParameterError, InvalidPointSetError
from .metrics import Bounded, QuasiNorm

__all__ = ["check_points", "nearest_distances", "auto_rho", "auto_R", "validate_radii"]


def check_points(points, name="points", min_points=1):
    """Return a float64 copy (N, n) of ``points``; raise on bad shapes, NaN/inf,
    duplicates (InvalidPointSetError naming the indices) or too few points."""
    p = np.array(points, dtype=float, copy=True)
    if p.ndim == 1:
        p = p[:, None]
    if p.ndim != 2 or p.shape[1] < 1:
        raise InvalidParameterError(name, f"expected an array of shape (N, n), got {np.shape(points)}")
    if p.shape[0] < min_points:
        raise InvalidPointSetError(f"{name}: need at least {min_points} points, got {p.shape[0]}")
    bad = np.flatnonzero(~np.all(np.isfinite(p), axis=1))
    if bad.size:
        raise InvalidPointSetError(f"{name}: non-finite coordinates (NaN or inf) at indices", bad)
    if p.shape[0] > 1:
        d, j = cKDTree(p).query(p, k=2)
        dup = np.flatnonzero(d[:, 1] == 0.0)
        if dup.size:
            raise InvalidPointSetError(f"{name}: duplicate points at indices", dup)
    return p


def nearest_distances(points, metric):
    """d_i = min_{j != i} d(x_i, x_j) in the metric, exact. Shape (N,)."""
    n_pts = points.shape[0]
    if n_pts < 2:
        return np.full(n_pts, np.inf)
    base = metric.base if isinstance(metric, Bounded) else metric
    if isinstance(base, QuasiNorm):
        d = _quasi_nearest(points, base)
    else:
        tree = cKDTree(base.tree_coords(points))
        d = tree.query(base.tree_coords(points), k=2, p=base.tree_p)[0][:, 1]
    if isinstance(metric, Bounded):
        d = d / (1.0 + d)
    return d


def _quasi_nearest(points, metric, k=16):
    """Nearest neighbour in the quasi-norm metric: k Euclidean (weighted) candidates,
    then a box-bounded check (|w y|_inf <= d^(1/p)) for the few points where the
    k-th candidate is not provably farther."""
    z = points * metric.w
    tree = cKDTree(z)
    k = min(k, points.shape[0])
    de, idx = tree.query(z, k=k, p=np.inf)
    cand = metric.norm(points[idx[:, 1:]] - points[:, None, :])
    best = cand.min(axis=1)
    unsure = np.flatnonzero(de[:, -1] <= best ** (1.0 / metric.p)) if k < points.shape[0] else []
    for i in unsure:
        js = tree.query_ball_point(z[i], best[i] ** (1.0 / metric.p) * (1 + 1e-12), p=np.inf)
        js = [j for j in js if j != i]
        best[i] = metric.norm(points[js] - points[i]).min()
    return best


def auto_rho(points, metric, fraction=0.5):
    """rho_i = fraction * nearest distance; fraction = 1/2 gives (34) (Remark 6)."""
    return fraction * nearest_distances(points, metric)


def _neighbour_max(points, metric):
    n_pts, n = points.shape
    base = metric.base if isinstance(metric, Bounded) else metric
    if n == 1:
        order = np.argsort(points[:, 0])
        gaps = base.norm(np.diff(points[order], axis=0))
        left = np.concatenate([[0.0], gaps])
        right = np.concatenate([gaps, [0.0]])
        out = np.empty(n_pts)
        out[order] = np.maximum(left, right)
        return out, True
    if n <= 6:
        try:
            tri = Delaunay(points)
            s = tri.simplices
            out = np.zeros(n_pts)
            for a in range(n + 1):
                for b in range(a + 1, n + 1):
                    d = base.norm(points[s[:, a]] - points[s[:, b]])
                    np.maximum.at(out, s[:, a], d)
                    np.maximum.at(out, s[:, b], d)
            if np.all(out > 0):
                return out, not isinstance(base, QuasiNorm)
        except QhullError:
            pass
    k = min(n + 2, n_pts)
    tree = cKDTree(points)
    idx = tree.query(points, k=k)[1]
    d = base.norm(points[idx[:, -1]] - points)
    return 2.0 * d, False


def auto_R(points, metric, margin=0.9):
    """Size radii R_i (see module doc). Returns (R (N,), guaranteed_cover: bool)."""
    if not (0 < margin <= 1):
        raise InvalidParameterError("margin", f"need 0 < margin <= 1, got {margin}")
    dmax, guaranteed = _neighbour_max(points, metric)
    R = dmax / margin
    if isinstance(metric, Bounded):
        R = R / (1.0 + R)
    return R, guaranteed


def validate_radii(rho, R, nearest, name_rho="rho", name_R="R"):
    """Check (16), (17): raise InvalidParameterError naming the offending indices."""
    rho = np.asarray(rho, float)
    R = np.asarray(R, float)
    for name, a in ((name_rho, rho), (name_R, R)):
        bad = np.flatnonzero(~(np.isfinite(a) & (a > 0)))
        if bad.size:
            raise InvalidParameterError(name, f"radii must be finite and > 0; bad at indices {bad[:10].tolist()}")
    bad = np.flatnonzero(rho > nearest * (1 + 1e-12))
    if bad.size:
        raise InvalidParameterError(
            name_rho, f"constraint (16) rho_i <= min_j d(x_i, x_j) violated at indices {bad[:10].tolist()}")
    bad = np.flatnonzero(rho > R)
    if bad.size:
        raise InvalidParameterError(
            name_R, f"constraint (17) rho_i <= R_i violated at indices {bad[:10].tolist()}")
