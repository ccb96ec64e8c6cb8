"""Qhull's Delaunay triangulation of scattered points, computed in normalised coordinates.

Qhull's precision thresholds are, in effect, relative to the largest coordinate, not to
the extent of the points: points 0.05 apart offset by 1e5 are "numerically coincident"
to it, and coordinates of 1e100 give a "flat" initial simplex. The Delaunay
triangulation is invariant under translations and uniform scalings, so it is computed for

    z = (x - c) * s,

e = 2^ceil(log2(extent)), s = 1 / e, and c the bounding-box centre rounded to a multiple
of 64 e: |z| <= 32.5 whatever the offset and scale of the points. For a box centred
within 32 e (32 to 64 extents) of the origin c = 0, and scaling by a power of two is
exact, so Qhull's triangulation is the one of the points themselves to the bit (ties of
co-circular points, e.g. grids, are broken as before). Boxes farther out are moved next
to the origin, the subtraction rounding only at the points' own precision; for them a
tie may be broken the other way (another, equally valid Delaunay triangulation).

:class:`Triangulation` answers in the caller's coordinates (``points``, ``transform``,
``find_simplex``) and shares the combinatorial arrays of Qhull's result (``simplices``,
``neighbors``, ``coplanar``, ``vertex_neighbor_vertices``).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import Delaunay, QhullError

from ..errors import InvalidPointSetError

__all__ = ["Triangulation", "delaunay", "normalizing_map", "delaunay_simplices"]


def normalizing_map(points):
    """(c (n,), s): the translation and power-of-two scale of the module doc, for points
    (N, n) with a positive, finite extent."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    ext = float((hi - lo).max())
    e = 2.0 ** int(np.ceil(np.log2(ext))) if ext > 0 else 1.0
    g = 64.0 * e
    c = g * np.round((0.5 * lo + 0.5 * hi) / g)
    return c + 0.0, 1.0 / e          # (+ 0.0: no -0.0 centres)


class Triangulation:
    """A scipy Delaunay triangulation of ``points`` built on normalised coordinates
    (module doc), presented in the caller's coordinates.

    Attributes: ``points`` (N, n) the caller's points; ``simplices`` (T, n+1),
    ``neighbors`` (T, n+1), ``coplanar``, ``vertex_neighbor_vertices`` as scipy's;
    ``transform`` (T, n+1, n) the barycentric transforms in the caller's coordinates
    (scipy's layout); ``qhull`` the scipy object (normalised coordinates ``z``);
    ``centre`` (n,), ``scale``: z = (x - centre) * scale.
    """

    def __init__(self, points, qhull, centre, scale):
        self.points, self.qhull, self.centre, self.scale = points, qhull, centre, scale
        self.simplices = qhull.simplices
        self.neighbors = qhull.neighbors
        self.coplanar = qhull.coplanar
        self._transform = None          # (the cache of :attr:`transform`, scipy's name)

    @property
    def ndim(self) -> int:
        return self.points.shape[1]

    @property
    def nsimplex(self) -> int:
        return len(self.simplices)

    @property
    def vertex_neighbor_vertices(self):
        return self.qhull.vertex_neighbor_vertices

    @property
    def transform(self) -> np.ndarray:
        """(T, n+1, n) barycentric transforms in the caller's coordinates (scipy's layout:
        lambda_{0..n-1} = T[:, :n] (x - T[:, n])); NaN rows for degenerate simplices.
        From Qhull's object's (normalised coordinates): the same bits when the map is a
        power-of-two scaling."""
        if self._transform is None:
            T = np.array(self.qhull.transform)
            n = self.ndim
            bad = np.isnan(T[:, 0, 0])
            T[:, :n] *= self.scale            # exact: a power of two
            T[:, n] = self.points[self.simplices[:, n]]
            T[bad] = np.nan
            self._transform = T
        return self._transform

    def normalize(self, x) -> np.ndarray:
        """x (..., n) in the normalised coordinates of :attr:`qhull`."""
        return (np.asarray(x, dtype=float) - self.centre) * self.scale

    def find_simplex(self, x, tol=None):
        """As scipy's ``find_simplex`` for points x (..., n) in the caller's coordinates
        (``tol`` is on barycentric coordinates, hence scale free)."""
        return self.qhull.find_simplex(self.normalize(x), tol=tol)


def _qhull(points):
    """(scipy Delaunay of the normalised points, centre, scale); QhullError passes."""
    c, s = normalizing_map(points)
    return Delaunay((points - c) * s), c, s


def delaunay(points) -> Triangulation:
    """The Delaunay triangulation of points (N, n), n >= 2 (normalised, module doc).

    Raises InvalidPointSetError naming ``points``: all the points when Qhull finds them
    degenerate (collinear, in a hyperplane), the dropped ones when Qhull finds some
    numerically coincident."""
    N, n = points.shape
    try:
        tri, c, s = _qhull(points)
    except QhullError as exc:
        what = "collinear" if n == 2 else "in a hyperplane"
        raise InvalidPointSetError(
            f"points: degenerate point set ({what}), no Delaunay triangulation: "
            + str(exc).splitlines()[0], np.arange(N)) from None
    if len(tri.coplanar):
        raise InvalidPointSetError("points: Qhull dropped these points (numerically coincident)",
                                   tri.coplanar[:, 0])
    return Triangulation(points, tri, c, s)


def delaunay_simplices(points):
    """Delaunay simplices (T, n+1) of points (N, n), 2 <= n, normalised as :func:`delaunay`;
    None when Qhull fails."""
    try:
        return _qhull(points)[0].simplices
    except QhullError:
        return None
