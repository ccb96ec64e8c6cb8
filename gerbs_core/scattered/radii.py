"""Point-set validation and the radii rho_i, R_i of the general construction.

Constraints (paper section 2.2, case (B), mesh-free Hermite interpolation):

* (16)  0 < rho_i <= min_{j != i} d(x_i, x_j)
* (17)  rho_i <= R_i < inf
* (13)  for ball covers Omega_i = B_d(x_i, R_i), max_{dOmega_i} d(x, x_i) = R_i holds.

Automatic choice:

* rho_i = 1/2 min_{j != i} d(x_i, x_j) (Remark 6), so the phi supports are
  disjoint, (34), and the simplified forms (35)/(36) apply;
* R_i from the local point spacing: ``factor`` times the distance to the
  (n+1)-th nearest neighbour (so each ball holds a few neighbours, whatever the
  density), then enlarged where needed until the balls of radius 0.9 R_i cover
  every simplex of the Delaunay simplicialization of the hull
  (:func:`gerbs_core.scattered.cover_check.certify_cover`, a proof, not a sample):
  psi_j >= b(0.9) somewhere at every point of the hull (Definition 11). Near
  the hull, where Delaunay simplices are long slivers, only the radii of the
  points next to a gap grow, so R_i stays O(local spacing) and each query sees
  O(1) balls. For n = 1 the simplices are the intervals between sorted points.
  Without a usable simplicialization (Qhull fails, n > 6, quasi-norms, whose
  balls are not convex) R_i is 2 x the distance to the (n+1)-th neighbour and
  the cover is not certified (``cover_report`` measures it).

Nearest-neighbour searches use one scipy.spatial.cKDTree of the points per fit
(built by :func:`check_points`, reused), N log N.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InvalidParameterError, InvalidPointSetError
from ..inputs import real_array
from .cover_check import certify_cover
from .metrics import QuasiNorm
from .triangulation import delaunay_simplices

__all__ = ["check_points", "check_extent", "nearest_distances", "auto_rho", "auto_R",
           "validate_radii", "simplicialization", "EXTENT_RANGE", "MARGIN"]

# the extents of point sets the interpolator handles: its Taylor coefficients of degree 3
# scale like extent^-3 and its squared distances like extent^2 (double precision:
# 1e-308 .. 1e308, with room for the data's own scale)
EXTENT_RANGE = (1e-100, 1e100)
# the certified automatic ball radii R_i cover the hull by the balls of radius MARGIN R_i
MARGIN = 0.9


def check_points(points, name="points", min_points=1, return_tree=False):
    """Return a float64 copy (N, n) of ``points``; raise on bad shapes, NaN/inf,
    duplicates (InvalidPointSetError naming the indices) or too few points.
    ``return_tree``: also return a cKDTree of the points (None for one point)."""
    p = real_array(name, points)
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
        dup = _duplicates(p)
        if dup.size:
            raise InvalidPointSetError(f"{name}: duplicate points at indices", dup)
        check_extent(p, name)
    if not return_tree:
        return p
    # sliding-midpoint splits, boxes not shrunk to the points: built in half the time,
    # the same neighbours (every query is exact); k-NN queries as fast (10^5 points)
    return p, (cKDTree(p, balanced_tree=False, compact_nodes=False) if p.shape[0] > 1 else None)


def check_extent(points, name="points", power=1.0, what=""):
    """Refuse points (N, n), N >= 2, whose extent (the longest side of their bounding box) is
    outside :data:`EXTENT_RANGE` (InvalidPointSetError naming ``name`` and the range); for a
    metric raising coordinates to a power p > 2.8 (l_p) the range narrows to
    [10^(-280/p), 10^(280/p)] (``what`` says which metric). The position of the box does
    not matter (the Delaunay triangulation is computed on centred coordinates)."""
    with np.errstate(over="ignore", invalid="ignore"):
        ext = float(np.max(np.ptp(points, axis=0)))
    e = min(np.log10(EXTENT_RANGE[1]), 280.0 / power)
    lo, hi = max(10.0 ** -e, EXTENT_RANGE[0]), 10.0 ** e
    if not lo <= ext <= hi:
        raise InvalidPointSetError(
            f"{name}: the extent of the points (the longest side of their bounding box) is "
            f"{ext:.3g}, outside the supported range [{lo:.3g}, {hi:.3g}]{what}; rescale the "
            f"coordinates (and any derivative data) to a moderate range")


def _duplicates(p):
    """Sorted indices of the points equal to another one (distance exactly 0).

    Equal points have equal first coordinates: the sorted first coordinates give the
    values that repeat (usually none: then no lexicographic sort at all), and only the
    points with such a value are sorted lexicographically, where equal rows are
    adjacent. The same indices as sorting all points (2.5x cheaper at 10^5 points)."""
    xs = np.sort(p[:, 0])
    rep = xs[1:][xs[1:] == xs[:-1]]
    if not rep.size:
        return np.empty(0, dtype=np.intp)
    cand = np.flatnonzero(np.isin(p[:, 0], rep))
    q = p[cand]
    o = np.lexsort(q.T[::-1])
    same = np.all(q[o[1:]] == q[o[:-1]], axis=1)
    dup = np.zeros(len(cand), bool)
    dup[o[1:][same]] = True
    dup[o[:-1][same]] = True
    return cand[dup]


def _tree_for(points, metric, tree):
    """A cKDTree in ``metric.tree_coords`` (the shared one when the weights are 1)."""
    if tree is not None and np.all(metric.w == 1.0):
        return tree
    return cKDTree(metric.tree_coords(points))


def nearest_distances(points, metric, tree=None):
    """d_i = min_{j != i} d(x_i, x_j) in the metric, exact. Shape (N,).
    ``tree``: an optional cKDTree of ``points`` to reuse."""
    n_pts = points.shape[0]
    if n_pts < 2:
        return np.full(n_pts, np.inf)
    base = metric.base
    if isinstance(base, QuasiNorm):
        d = _quasi_nearest(points, base)
    else:
        t = _tree_for(points, base, tree)
        d = t.query(base.tree_coords(points), k=2, p=base.tree_p)[0][:, 1]
    return metric.from_base_radius(d)


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


def auto_rho(points, metric, fraction=0.5, tree=None):
    """rho_i = fraction * nearest distance; fraction = 1/2 gives (34) (Remark 6)."""
    return fraction * nearest_distances(points, metric, tree)


def simplicialization(points):
    """Simplices (T, n+1) int covering the convex hull: sorted intervals for n = 1,
    Qhull's Delaunay for 2 <= n <= 6 (on normalised coordinates,
    :mod:`~gerbs_core.scattered.triangulation`); None when Qhull fails or n > 6."""
    n_pts, n = points.shape
    if n == 1:
        order = np.argsort(points[:, 0])
        return np.stack([order[:-1], order[1:]], axis=1)
    if n > 6 or n_pts < n + 1:
        return None
    return delaunay_simplices(points)


def _local_spacing(points, base, tree, k):
    """Base-norm distance to the k-th nearest (Euclidean) neighbour, (N,)."""
    k = min(k, points.shape[0] - 1)
    idx = tree.query(points, k=k + 1)[1][:, 1:]
    return base.norm(points[idx] - points[:, None, :]).max(axis=1)


def auto_R(points, metric, margin=MARGIN, factor=2.0, tree=None, simplices="auto"):
    """Size radii R_i (see module doc). Returns (R (N,), certified: bool).

    ``tree``: cKDTree of ``points`` to reuse; ``simplices``: (T, n+1) simplices of the
    hull to certify on ("auto": :func:`simplicialization`; None: no certificate).
    """
    if not (0 < margin <= 1):
        raise InvalidParameterError("margin", f"need 0 < margin <= 1, got {margin}")
    n_pts, n = points.shape
    tree = cKDTree(points) if tree is None else tree
    base = metric.base
    spacing = _local_spacing(points, base, tree, n + 1)
    if isinstance(simplices, str):
        simplices = simplicialization(points) if metric.convex else None
    if simplices is None or not metric.convex:
        return metric.from_base_radius(2.0 * spacing), False
    Rb, _ = certify_cover(points, simplices, factor * spacing, base, tree, margin=margin)
    return metric.from_base_radius(Rb), True


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
