"""Cover diagnostics: thickness eps0 (Definition 11), overlap counts and the
condition of the rational form Psi_i = psi_i / sum_k psi_k (27).

All quantities are *estimates on a sample* of the domain (a minimum over a
continuum cannot be computed exactly): by default a barycentric lattice of
resolution ``resolution`` in every Delaunay simplex of the points (n = 2; it
contains the vertices, edges and interiors of every triangle, where eps0 is
typically attained on edges and at hull slivers), random barycentric points in
the Delaunay simplices for n >= 3 (the cover's own simplices for the n-D star cover),
and a regular grid inside the domain polygon for the Voronoi cover.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from ..inputs import integer, real_array

from .covers import in_convex_polygon
from .triangulation import delaunay_simplices

__all__ = ["sample_domain", "cover_report"]


def _lattice(r):
    ij = [(i, j) for i in range(r + 1) for j in range(r + 1 - i)]
    lam = np.array([(r - i - j, i, j) for i, j in ij], float) / r
    return lam


def sample_domain(interp, resolution=6, seed=0):
    """Sample points (M, n) of the interpolator's domain (see module doc)."""
    pts = interp.points
    n = pts.shape[1]
    if getattr(interp, "domain", None) is not None:
        lo, hi = interp.domain.min(0), interp.domain.max(0)
        k = max(int(resolution * np.sqrt(len(pts))), 10)
        g = np.stack(np.meshgrid(np.linspace(lo[0], hi[0], k), np.linspace(lo[1], hi[1], k)), -1).reshape(-1, 2)
        return g[in_convex_polygon(g, interp.domain)]
    if n == 1:
        x = np.sort(pts[:, 0])
        t = np.linspace(0, 1, resolution + 1)
        return (x[:-1, None] + np.diff(x)[:, None] * t).reshape(-1, 1)
    simp = interp.simplices if hasattr(interp, "simplices") else delaunay_simplices(pts)
    if simp is None:
        raise InvalidParameterError("samples", "Qhull finds the points degenerate: no simplices "
                                    "to sample the domain in; pass samples")
    if n == 2:
        lam = _lattice(resolution)
    else:
        rng = np.random.default_rng(seed)
        lam = rng.dirichlet(np.ones(n + 1), size=resolution ** 2)
        lam = np.concatenate([lam, np.eye(n + 1)])
    return np.einsum("sk,tkn->tsn", lam, pts[simp]).reshape(-1, n)


def cover_report(interp, samples=None, resolution=6):
    """Diagnostics of the cover of ``interp`` on ``samples`` (default: sample_domain).

    Returns a dict:
      eps0        min over samples of max_i psi_i(x) (Definition 11; > 0 means thick)
      min_sum     min over samples of sum_i psi_i(x)
      condition   1 / min_sum: the largest amplification in Psi = psi / sum psi (27)
      max_overlap, mean_overlap  number of elements with psi_i(x) > 0
      n_samples, outside (samples where no psi is positive)
    """
    integer("resolution", resolution, 1)
    x = sample_domain(interp, resolution) if samples is None else real_array("samples", samples)
    if x.ndim != 2 or x.shape[1] != interp.n:
        raise InvalidParameterError("samples", f"must have shape (M, {interp.n}), got {x.shape}")
    maxpsi, sums, counts = [], [], []
    for s in range(0, len(x), interp.chunk_size):
        xc = x[s:s + interp.chunk_size]
        idx, edge = interp._candidates(xc)
        psi, _ = interp._jets(xc, idx, edge, 0)
        v = psi[0]
        maxpsi.append(v.max(axis=1) if v.shape[1] else np.zeros(len(xc)))
        sums.append(v.sum(axis=1))
        counts.append((v > 0).sum(axis=1))
    maxpsi, sums, counts = map(np.concatenate, (maxpsi, sums, counts))
    min_sum = float(sums.min())
    return {
        "eps0": float(maxpsi.min()),
        "min_sum": min_sum,
        "condition": float(1.0 / min_sum) if min_sum > 0 else np.inf,
        "max_overlap": int(counts.max()),
        "mean_overlap": float(counts.mean()),
        "n_samples": int(len(x)),
        "outside": int((sums == 0).sum()),
    }
