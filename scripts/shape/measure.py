"""Figures of one output mesh against its input (the same rules for every method).

``measure(case, out)`` -> dict of figures (NaN where not defined):
  P, T                 output points and triangles; ``orient``: orientation defects
  dmax, drms           |signed distance| of all output points to the exact surface
  nmax                 largest angle (deg) between the output's angle-weighted
                       vertex normal and the exact normal at the closest point
  nxmax                the same with the method's own normals (GERBS: exact dS)
  Hrms, Hmax           cotangent mean curvature (Meyer et al.) minus the exact H at
                       the closest point, over the curvature region (below)
  Hmin, Hspread        min and 95-5 percentile range of the cotangent H there
  Hxrms, Hxmax, Hxmin  the same from the method's exact derivatives (GERBS)
  box                  (3,) output box extent / cage box extent per axis
  f60, f90, fmax       adjacent output triangle pairs above 60 / 90 degrees, largest
  zebra, zebra_fine    zebra stripes: the pieces the bands break into per environment
                       direction, those covering at least 1e-3 / 1e-4 of the area (the
                       zebra shader's default density, 24 directions, the vertex normals;
                       gerbs_core.testing.stripe_components): fewer is fairer
Curvature region: interior output vertices (every vertex of a closed mesh); for
inputs with a ``margin`` (height fields) only those at least ``margin`` from the
domain's boundary in x and y, where no boundary rule acts.
"""
from __future__ import annotations

import numpy as np

from gerbs_core.testing import (
    box_ratio,
    cotangent_mean_curvature,
    dihedral_angles,
    edge_adjacency,
    observed_order,
    stripe_components,
    vertex_normals,
)

# figures whose observed order under refinement is reported
ORDER_KEYS = ("dmax", "drms", "nmax", "nxmax", "Hrms", "Hmax", "Hxrms", "Hxmax")


def _angle(a, b):
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1),
                                 np.einsum("ij,ij->i", a, b)))


def _stats(err):
    err = err[np.isfinite(err)]
    if not len(err):
        return np.nan, np.nan
    return float(np.sqrt(np.mean(err ** 2))), float(np.abs(err).max())


def _nanmin(x):
    x = x[np.isfinite(x)]
    return float(x.min()) if len(x) else np.nan


def measure(case, out) -> dict:
    P = np.asarray(out["points"], dtype=np.float64)
    T = np.asarray(out["triangles"], dtype=np.int64)
    adj = edge_adjacency(T)
    ang = dihedral_angles(P, T, adj)
    nd = vertex_normals(P, T)
    row = {"P": len(P), "T": len(T), "orient": int(np.sum(adj["same_direction"])),
           "box": box_ratio(P, case.V),
           "f60": int(np.sum(ang > 60)), "f90": int(np.sum(ang > 90)),
           "fmax": float(ang.max()) if len(ang) else 0.0}
    row["zebra"], row["zebra_fine"] = stripe_components(P, T, nd, min_area=(1e-3, 1e-4))
    H, inner = cotangent_mean_curvature(P, T, nd, adj)
    region = inner.copy()
    if case.margin > 0:
        region &= np.min(1.0 - np.abs(P[:, :2]), axis=1) >= case.margin
    Hr = H[region]
    row["Hmin"] = _nanmin(Hr)
    fin = Hr[np.isfinite(Hr)]
    row["Hspread"] = float(np.ptp(np.percentile(fin, [5, 95]))) if len(fin) else np.nan
    Hx = out.get("H_exact")
    # exact-derivative curvature over the same region (boundary vertices included
    # when there is no margin: the derivatives exist there)
    xreg = region | (~inner if case.margin == 0 else False)
    row["Hxmin"] = _nanmin(np.asarray(Hx)[xreg]) if Hx is not None else np.nan
    for k in ("dmax", "drms", "nmax", "nxmax", "Hrms", "Hmax", "Hxrms", "Hxmax"):
        row.setdefault(k, np.nan)
    if case.exact is not None:
        d, n, He = case.exact.closest(P)
        row["drms"], row["dmax"] = _stats(d)
        row["nmax"] = float(np.nanmax(_angle(nd, n)))
        if out.get("normals") is not None:
            row["nxmax"] = float(np.nanmax(_angle(np.asarray(out["normals"]), n)))
        row["Hrms"], row["Hmax"] = _stats(Hr - He[region])
        if Hx is not None:
            row["Hxrms"], row["Hxmax"] = _stats(np.asarray(Hx)[xreg] - He[xreg])
    return row


def orders(cases, rows):
    """Observed order of every figure of ORDER_KEYS over the refinement ``cases``
    (against their mean cage edge length) from ``rows`` [figures of each case]:
    the least-squares slope over all, and as ``<key>@last`` over the last two."""
    h = [c.h for c in cases]
    out = {k: observed_order(h, [r[k] for r in rows]) for k in ORDER_KEYS}
    out.update({f"{k}@last": observed_order(h[-2:], [r[k] for r in rows[-2:]]) for k in ORDER_KEYS})
    return out
