"""Vertex charts zeta_v: unfold the faces around v, keep radii, scale angles (DESIGN section 5).

Around vertex v the faces of its star are laid side by side in the plane in
counter-clockwise order (each D_f at its corner angle alpha), giving the
*unfolded* polar coordinates (r, theta) with theta in [0, T_v), T_v = sum of the
corner angles at v. The chart is

    zeta_v = r (cos(s_v theta), sin(s_v theta)),

with s_v = 2 pi / T_v for interior vertices (the star closes up exactly) and, for
boundary vertices (open fan starting at the boundary face whose first edge
v -> next is a border edge): rule ``"keep"`` s_v = 1 (a flat metric mesh is then
charted isometrically), compressed to s_v = 1.5 pi / T_v when T_v > 1.5 pi so that
the chart stays injective; rule ``"straighten"`` s_v = pi / T_v (the border is a
straight line through v). Per-vertex scales may be given instead (``scale``: the
copies of a creased vertex, :mod:`gerbs_core.mesh.creases`: pi / T_v to straighten
a crease chain through v, 2 pi / T_v for the full-disc chart of a dart).

Two faces sharing a spoke unfold isometrically into one plane and angle scaling
about a point is smooth away from it, so chart transitions are C-infinity on
overlaps. The maps below are exact (closed form), with first and second
derivatives with respect to the face-local coordinates of D_f.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["VertexCharts", "vertex_charts", "BOUNDARY_RULES"]

BOUNDARY_RULES = ("keep", "straighten")
KEEP_MAX_SPAN = 1.5 * np.pi


@dataclass(frozen=True)
class VertexCharts:
    """Charts of all vertices, stored per corner.

    Per vertex (V,): ``scale`` s_v, ``span`` T_v (sum of corner angles),
    ``boundary`` (bool). Per corner (C,): ``theta0`` start angle of the corner's
    sector in the unfolded star, ``origin`` (C,2) the corner's position in its
    face frame, ``beta`` the face-frame angle of the edge corner -> next corner,
    ``alpha`` the corner angle. ``corner_vertex`` (C,) = face_vertices.
    """

    scale: np.ndarray
    span: np.ndarray
    boundary: np.ndarray
    theta0: np.ndarray
    origin: np.ndarray
    beta: np.ndarray
    alpha: np.ndarray
    corner_vertex: np.ndarray
    rule: str

    # cos and sin of beta, once per corner (every evaluation of a chart rotates by them)
    @cached_property
    def _beta_cos(self) -> np.ndarray:
        return np.cos(self.beta)

    @cached_property
    def _beta_sin(self) -> np.ndarray:
        return np.sin(self.beta)

    def unfolded(self, corner: np.ndarray, x: np.ndarray):
        """Unscaled unfolded polar coordinates (r, theta) of face points x (...,2).

        corner (...) int: the corner (of the face containing x) whose vertex's
        chart is wanted. theta = theta0 + angle from the corner's first edge;
        for points of the face it lies in the sector [theta0, theta0 + alpha].
        """
        corner = np.asarray(corner)
        d = np.asarray(x, dtype=np.float64) - self.origin[corner]
        cb, sb = self._beta_cos[corner], self._beta_sin[corner]
        a = np.arctan2(cb * d[..., 1] - sb * d[..., 0], cb * d[..., 0] + sb * d[..., 1])
        return np.hypot(d[..., 0], d[..., 1]), self.theta0[corner] + a

    def polar(self, corner, x, nu: int = 0, clamp: bool = True):
        """Unfolded polar coordinates (r, theta) of face points and their derivatives.

        Returns [(r, theta)], then [(dr, dtheta)] (each (..., 2)), then
        [(Hr, Htheta)] (each (..., 2, 2)) up to order nu, w.r.t. face coordinates.
        Exact; derivatives are set to 0 at r = 0.
        """
        corner = np.asarray(corner)
        d = np.asarray(x, dtype=np.float64) - self.origin[corner]
        cb, sb = self._beta_cos[corner], self._beta_sin[corner]
        a = np.arctan2(cb * d[..., 1] - sb * d[..., 0], cb * d[..., 0] + sb * d[..., 1])
        if clamp:
            a = np.clip(a, 0.0, self.alpha[corner])
        r = np.hypot(d[..., 0], d[..., 1])
        out = [(r, self.theta0[corner] + a)]
        if nu < 1:
            return out
        zero = r == 0
        rs = np.where(zero, 1.0, r)
        dr = d / rs[..., None]
        dt = np.stack([-d[..., 1], d[..., 0]], axis=-1) / (rs * rs)[..., None]
        dr[zero] = 0.0
        dt[zero] = 0.0
        out.append((dr, dt))
        if nu < 2:
            return out
        d1, d2 = d[..., 0], d[..., 1]
        r3, r4 = rs ** 3, rs ** 4
        Hr = np.empty(d.shape + (2,))
        Hr[..., 0, 0] = d2 * d2 / r3
        Hr[..., 1, 1] = d1 * d1 / r3
        Hr[..., 0, 1] = Hr[..., 1, 0] = -d1 * d2 / r3
        Ht = np.empty(d.shape + (2,))
        Ht[..., 0, 0] = 2 * d1 * d2 / r4
        Ht[..., 1, 1] = -2 * d1 * d2 / r4
        Ht[..., 0, 1] = Ht[..., 1, 0] = (d2 * d2 - d1 * d1) / r4
        Hr[zero] = 0.0
        Ht[zero] = 0.0
        out.append((Hr, Ht))
        return out

    def to_chart(self, corner, x, nu: int = 0, clamp: bool = True, pol=None):
        """zeta_v(x) for face points x (..., 2); returns [y, dy, d2y] up to order nu.

        y (..., 2); dy (..., 2, 2) with dy[..., i, j] = d y_i / d x_j; d2y
        (..., 2, 2, 2) with d2y[..., i, j, k] = d^2 y_i / d x_j d x_k. Exact. At
        the vertex itself (r = 0) y = 0 and the derivatives are set to 0 (the map
        is only continuous there when s_v != 1). clamp: clip the in-face angle to
        [0, alpha] (points of the face; removes round-off across the sector's
        rays so boundary sectors never wrap around).
        """
        corner = np.asarray(corner)
        if pol is None or len(pol) < nu + 1:
            pol = self.polar(corner, x, nu, clamp)
        r, th = pol[0]
        s = self.scale[self.corner_vertex[corner]]
        phi = s * th
        cp, sp = np.cos(phi), np.sin(phi)
        out = [np.stack([r * cp, r * sp], axis=-1)]
        if nu < 1:
            return out
        dr, dpsi = pol[1]
        sdp = s[..., None] * dpsi
        dy1 = cp[..., None] * dr - (r * sp)[..., None] * sdp
        dy2 = sp[..., None] * dr + (r * cp)[..., None] * sdp
        out.append(np.stack([dy1, dy2], axis=-2))
        if nu < 2:
            return out
        Hr, Hp = pol[2]
        ss = s[..., None, None]
        sym = dr[..., :, None] * dpsi[..., None, :] + dpsi[..., :, None] * dr[..., None, :]
        pp = dpsi[..., :, None] * dpsi[..., None, :]
        C, S, R = cp[..., None, None], sp[..., None, None], r[..., None, None]
        h1 = C * Hr - S * ss * sym - R * C * ss * ss * pp - R * S * ss * Hp
        h2 = S * Hr + C * ss * sym - R * S * ss * ss * pp + R * C * ss * Hp
        out.append(np.stack([h1, h2], axis=-3))
        return out

    def from_chart(self, v: int, y: np.ndarray, star_corners: np.ndarray):
        """Inverse chart of vertex v: chart points y (N,2) -> (corner (N,), x (N,2)).

        star_corners: v's corners in star order. Points outside the unfolded star
        (beyond its far edges) are mapped anyway (the face is found by angle).
        """
        y = np.asarray(y, dtype=np.float64)
        s = self.scale[v]
        phi = np.arctan2(y[:, 1], y[:, 0])
        if not self.boundary[v] or s * self.span[v] >= 2.0 * np.pi * (1.0 - 1e-12):
            phi = np.mod(phi, 2.0 * np.pi)
        else:
            phi = np.where(phi < -0.25 * np.pi, phi + 2.0 * np.pi, phi)
        theta = phi / s
        th0 = self.theta0[star_corners]
        j = np.clip(np.searchsorted(th0, theta, side="right") - 1, 0, len(th0) - 1)
        c = np.asarray(star_corners)[j]
        a = theta - self.theta0[c] + self.beta[c]
        r = np.hypot(y[:, 0], y[:, 1])
        x = self.origin[c] + r[:, None] * np.stack([np.cos(a), np.sin(a)], axis=-1)
        return c, x


def vertex_charts(topo, corners2d, angles, rule: str = "keep", scale=None) -> VertexCharts:
    """Build all vertex charts of a :class:`~gerbs_core.mesh.topology.MeshTopology`.

    corners2d (C,2), angles (C,): the face layouts (:mod:`gerbs_core.mesh.layout`).
    Stars are the topology's ordered stars (counter-clockwise; boundary fans start
    at the face whose edge v -> next is a border edge). scale (V,) optional: s_v where
    finite (the others by the rule).
    """
    if rule not in BOUNDARY_RULES:
        raise InvalidParameterError("boundary", f"must be one of {BOUNDARY_RULES}, got {rule!r}")
    fv = np.asarray(topo.face_vertices, dtype=np.int64)
    nxt = topo.corner_next
    so = np.asarray(topo.star_offsets, dtype=np.int64)
    sc = np.asarray(topo.star_corners, dtype=np.int64)
    boundary = np.asarray(topo.vertex_is_boundary, dtype=bool)
    V = len(so) - 1
    scale_override = None if scale is None else np.asarray(scale, dtype=np.float64)
    ang_sorted = angles[sc]
    cum = np.cumsum(ang_sorted)
    vid = np.repeat(np.arange(V), np.diff(so))
    start = np.concatenate([[0.0], cum])[so[:-1]]
    excl = cum - ang_sorted - start[vid]  # exclusive cumulative angle within each star
    theta0 = np.zeros(len(fv))
    theta0[sc] = excl
    span = np.add.reduceat(ang_sorted, so[:-1]) if len(sc) else np.zeros(V)
    span = np.where(np.diff(so) > 0, span, 0.0)
    scale = np.where(boundary, 1.0, 2.0 * np.pi / np.where(span > 0, span, 1.0))
    if rule == "keep":
        wide = boundary & (span > KEEP_MAX_SPAN)
        scale = np.where(wide, KEEP_MAX_SPAN / np.where(span > 0, span, 1.0), scale)
    else:
        scale = np.where(boundary, np.pi / np.where(span > 0, span, 1.0), scale)
    if scale_override is not None:
        scale = np.where(np.isfinite(scale_override), scale_override, scale)
    e = corners2d[nxt] - corners2d
    beta = np.arctan2(e[:, 1], e[:, 0])
    return VertexCharts(scale=scale, span=span, boundary=boundary, theta0=theta0,
                        origin=np.asarray(corners2d, dtype=np.float64), beta=beta,
                        alpha=np.asarray(angles, dtype=np.float64), corner_vertex=fv, rule=rule)
