"""The surface seen from a vertex chart: S o zeta_v^{-1} and its chart derivatives.

Smoothness is a statement in charts: at a vertex v the smooth structure is the
chart zeta_v, so the tests differentiate S o zeta_v^{-1} across v's spokes from
both sides (``corner`` forces the face) and compare.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from .surface_inputs import inside_faces

__all__ = ["chart_evaluate"]


def chart_evaluate(surface, v: int, y, nu: int = 0, corner=None):
    """[S (N,3), dS/dy (N,3,2), d2S/dy2 (N,3,2,2)] up to nu at chart points y (N, 2) of
    vertex v; see :meth:`gerbs_core.mesh.surface.BlendingSurface.chart_evaluate`."""
    y = np.atleast_2d(np.asarray(y, dtype=np.float64))
    topo, ch = surface.model.topology, surface.charts
    star = topo.star_corners[topo.star_offsets[v]:topo.star_offsets[v + 1]]
    c, x = ch.from_chart(v, y, star)
    if corner is not None:
        c = np.full(len(y), int(corner))
        s = ch.scale[v]
        mid = ch.theta0[c] + 0.5 * ch.alpha[c]
        phi = np.arctan2(y[:, 1], y[:, 0])
        phi = s * mid + np.angle(np.exp(1j * (phi - s * mid)))  # branch nearest the sector
        a = phi / s - ch.theta0[c] + ch.beta[c]
        r = np.hypot(y[:, 0], y[:, 1])
        x = ch.origin[c] + r[:, None] * np.stack([np.cos(a), np.sin(a)], axis=-1)
    f = topo.corner_face[c]
    outside = np.flatnonzero(~inside_faces(f, x, surface.layouts.corners, topo.face_offsets))
    if len(outside):
        raise InvalidParameterError(
            "y", f"{len(outside)} chart point(s) of vertex {v} lie outside its star (first "
            f"indices {outside[:5].tolist()}, e.g. {y[outside[0]].tolist()})"
            + (f" or outside corner {int(corner)}'s face" if corner is not None else "")
            + ": the surface is defined on the faces only")
    out = surface._evaluate_at(f, x, nu, (len(f),))
    if nu == 0:
        return out
    yy = ch.to_chart(c, x, nu, clamp=False)
    Jinv = np.linalg.inv(yy[1])  # dx/dy
    res = [out[0], np.einsum("pcj,pji->pci", out[1], Jinv)]
    if nu >= 2:
        # d2S/dy2 = Jinv^T (H_x S - sum_i dS/dy_i H_x y_i) Jinv
        Hc = out[2] - np.einsum("pci,pijk->pcjk", res[1], yy[2])
        res.append(np.einsum("pcjk,pja,pkb->pcab", Hc, Jinv, Jinv))
    return res
