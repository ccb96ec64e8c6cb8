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
straight line through v).

Two faces sharing a spoke unfold isometrically into one plane and angle scaling
about a point is smooth away from it, so chart transitions are C-infinity on
overlaps. The maps below are exact (closed form), with first and second
derivatives with respect to the face-local coordinates of D_f.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InvalidParameterError

__all__ = ["VertexCharts", "vertex_charts", "corner_links", "BOUNDARY_RULES"]

BOUNDARY_RULES = ("keep", "straighten")
KEEP_MAX_SPAN = 1.5 * np.pi


def corner_links(face_offsets: np.ndarray, face_vertices: np.ndarray):
    """(corner_face (C,), next_corner (C,), prev_corner (C,)) of CSR faces."""
    off = np.asarray(face_offsets, dtype=np.int64)
    C = int(off[-1])
    sizes = np.diff(off)
    corner_face = np.repeat(np.arange(len(sizes)), sizes)
    nxt = np.arange(C) + 1
    nxt[off[1:] - 1] = off[:-1]
    prv = np.arange(C) - 1
    prv[off[:-1]] = off[1:] - 1
    return corner_face, nxt, prv


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

    def unfolded(self, corner: np.ndarray, x: np.ndarray):
        """Unscaled unfolded polar coordinates (r, theta) of face points x (...,2).

        corner (...) int: the corner (of the face containing x) whose vertex's
        chart is wanted. theta = theta0 + angle from the corner's first edge;
        for points of the face it lies in the sector [theta0, theta0 + alpha].
        """
        corner = np.asarray(corner)
        d = np.asarray(x, dtype=np.float64) - self.origin[corner]
        b = self.beta[corner]
        cb, sb = np.cos(b), np.sin(b)
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
        b = self.beta[corner]
        cb, sb = np.cos(b), np.sin(b)
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
        if not self.boundary[v]:
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


def vertex_charts(face_offsets, face_vertices, corners2d, angles, star_offsets,
                  star_corners, boundary, rule: str = "keep") -> VertexCharts:
    """Build all vertex charts.

    corners2d (C,2), angles (C,): from :func:`gerbs_core.face_shapes.face_shapes`.
    star_offsets (V+1,), star_corners (C,): each vertex's corners in counter-
    clockwise order (corner j+1's face shares the spoke v -> prev(corner j));
    for boundary vertices starting at the face whose edge v -> next is a border
    edge. boundary (V,) bool.
    """
    if rule not in BOUNDARY_RULES:
        raise InvalidParameterError("boundary", f"must be one of {BOUNDARY_RULES}, got {rule!r}")
    fv = np.asarray(face_vertices, dtype=np.int64)
    _, nxt, _ = corner_links(face_offsets, fv)
    so = np.asarray(star_offsets, dtype=np.int64)
    sc = np.asarray(star_corners, dtype=np.int64)
    boundary = np.asarray(boundary, dtype=bool)
    V = len(so) - 1
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
    e = corners2d[nxt] - corners2d
    beta = np.arctan2(e[:, 1], e[:, 0])
    return VertexCharts(scale=scale, span=span, boundary=boundary, theta0=theta0,
                        origin=np.asarray(corners2d, dtype=np.float64), beta=beta,
                        alpha=np.asarray(angles, dtype=np.float64), corner_vertex=fv, rule=rule)


def _sector_boundary(topo, charts: VertexCharts, corners2d: np.ndarray, c: int):
    """Polar (theta, r) of the far corners next(c) ... prev(c) of corner c's face, in order."""
    off = topo.face_offsets
    f = topo.corner_face[c]
    n = off[f + 1] - off[f]
    k = c - off[f]
    far = off[f] + (k + 1 + np.arange(n - 1)) % n
    r, t = charts.unfolded(np.full(len(far), c), corners2d[far])
    return t, r


def star_boundary(topo, charts: VertexCharts, corners2d: np.ndarray, v: int, first=0, last=None):
    """Polar vertices (theta (K+1,), radius (K+1,)) of v's unfolded star boundary.

    The boundary is the far edges of the incident faces (those not touching v) in
    counter-clockwise order; closed stars repeat the first vertex at theta + T.
    first/last: restrict to the sectors first..last (an open chain).
    """
    so = topo.star_offsets
    star = topo.star_corners[so[v]:so[v + 1]]
    sub = star[first:(len(star) if last is None else last + 1)]
    parts = [_sector_boundary(topo, charts, corners2d, c) for c in sub]
    th = [p[0][:-1] for p in parts] + [parts[-1][0][-1:]]
    rr = [p[1][:-1] for p in parts] + [parts[-1][1][-1:]]
    th, rr = np.concatenate(th), np.concatenate(rr)
    if not charts.boundary[v] and first == 0 and last is None:
        th[-1], rr[-1] = th[0] + charts.span[v], rr[0]
    return th, rr


def far_corner_polar(topo, charts: VertexCharts, corners2d):
    """Per corner c: unfolded polar (theta, r) of its face's corners next(c) ... prev(c).

    Returns three lists indexed by corner: theta and r (arrays of length n-1),
    computed with one vectorized call per face size, and a bytes signature of the
    sector's shape (equal signatures: congruent sectors).
    """
    sizes = topo.face_sizes
    cf, off = topo.corner_face, topo.face_offsets
    th_l = [None] * topo.n_corners
    r_l = [None] * topo.n_corners
    sig = [None] * topo.n_corners
    for n in np.unique(sizes).tolist():
        cs = np.flatnonzero(sizes[cf] == n)
        k = cs - off[cf[cs]]
        idx = off[cf[cs]][:, None] + (k[:, None] + 1 + np.arange(n - 1)[None, :]) % n
        r, t = charts.unfolded(np.broadcast_to(cs[:, None], idx.shape), corners2d[idx])
        # shape signature of the sector (angles relative to its start, radii), rounded
        key = np.round(np.concatenate([t - t[:, :1], r], axis=1), 11)
        for c, tt, rr, kk in zip(cs.tolist(), t, r, key):
            th_l[c], r_l[c], sig[c] = tt, rr, kk.tobytes()
    return th_l, r_l, sig


# Process-wide memo of envelopes (immutable objects) by exact star shape and settings:
# in mode "regular" a handful of star shapes recur in every mesh, and a rebuild after a
# settings change (Blender add-on) reuses them. clear_envelope_cache() empties it
# (the benchmark does, to time cold builds).
_ENVELOPE_CACHE: dict = {}
_ENVELOPE_CACHE_SIZE = 4096


def clear_envelope_cache() -> None:
    """Forget all memoized star envelopes."""
    _ENVELOPE_CACHE.clear()


def build_envelopes(topo, charts: VertexCharts, corners2d, kappa=0.8, shrink=0.95,
                    exact=False, kernel=None):
    """Smooth star envelopes (:class:`gerbs_core.gauge.envelope.RadialEnvelope`) of all charts.

    Returns (envelopes (list), corner_envelope (C,) int, corner_offset (C,)): the
    envelope serving each corner's sector, evaluated at theta - corner_offset.
    One closed envelope per interior vertex, one open envelope per boundary
    fan (its unfolded span may exceed 2*pi in mode "regular": the envelope is
    a function of the unfolded angle, only the chart angle is compressed).
    Stars of the same shape up to rotation (e.g. equal valence and
    face sizes in mode "regular") share one object.
    """
    from .gauge.envelope import RadialEnvelope
    cache, envs = {}, []
    corner_env = np.full(topo.n_corners, -1, dtype=np.int64)
    env_offset = np.zeros(topo.n_corners)
    so = topo.star_offsets
    th_l, r_l, sig = far_corner_polar(topo, charts, corners2d)
    settings = (float(kappa), float(shrink), bool(exact), kernel)

    def get(sigs, closed, make):
        key = (closed, settings, tuple(sigs))
        j = cache.get(key)
        if j is None:
            env = _ENVELOPE_CACHE.get(key)
            if env is None:
                th, r = make()
                env = RadialEnvelope(th - th[0], r, closed=closed, kappa=kappa, shrink=shrink,
                                     kernel=kernel, exact=exact)
                if len(_ENVELOPE_CACHE) >= _ENVELOPE_CACHE_SIZE:
                    _ENVELOPE_CACHE.pop(next(iter(_ENVELOPE_CACHE)))
                _ENVELOPE_CACHE[key] = env
            envs.append(env)
            j = cache[key] = len(envs) - 1
        return j

    def chain(star):
        th = [th_l[c][:-1] for c in star] + [th_l[star[-1]][-1:]]
        rr = [r_l[c][:-1] for c in star] + [r_l[star[-1]][-1:]]
        return np.concatenate(th), np.concatenate(rr)

    def closed_chain(rot, T):
        base = charts.theta0[rot[0]]
        th = np.concatenate([th_l[c][:-1] - base for c in rot] + [[T]])
        th[:-1] = np.where(th[:-1] < -1e-9 * T, th[:-1] + T, th[:-1])  # after the seam: + T
        th[0] = 0.0
        rr = np.concatenate([r_l[c][:-1] for c in rot] + [r_l[rot[0]][:1]])
        return th, rr

    for v in range(topo.n_vertices):
        star = topo.star_corners[so[v]:so[v + 1]].tolist()
        sigs = [sig[c] for c in star]
        if not charts.boundary[v]:
            # canonical rotation (smallest sector-signature sequence), so that rotated
            # copies of one star shape share an envelope
            k = len(star)
            j = min(range(k), key=lambda i: sigs[i:] + sigs[:i])
            rot = star[j:] + star[:j]
            T = charts.span[v]
            e = get(sigs[j:] + sigs[:j], True, lambda: closed_chain(rot, T))
            corner_env[star] = e
            env_offset[star] = charts.theta0[rot[0]]
            continue
        e = get(sigs, False, lambda: chain(star))
        corner_env[star] = e
        env_offset[star] = th_l[star[0]][0]
    return envs, corner_env, env_offset


def eval_envelopes(envelopes, corner_env, env_offset, corners: np.ndarray, theta: np.ndarray,
                   nu: int):
    """[u~, u~', u~''] (up to nu), u~ = 1/rho~, of the envelope serving each corner.

    theta (..., P): unfolded angles (chart of the corner's vertex); corners either
    of theta's shape or of shape theta.shape[:-1] (one corner per row of P
    samples: grouping then works on rows, cheaply).
    """
    theta = np.asarray(theta, dtype=np.float64)
    corners = np.asarray(corners)
    if corners.shape == theta.shape:
        rows_c, th2 = corners.reshape(-1, 1), theta.reshape(-1, 1)
    else:
        rows_c, th2 = corners.reshape(-1), theta.reshape(-1, theta.shape[-1])
        rows_c = rows_c[:, None]
    rows_c = rows_c[:, 0]
    out = np.empty((nu + 1,) + th2.shape)
    e = corner_env[rows_c]
    order = np.argsort(e, kind="stable")
    es = e[order]
    cut = np.flatnonzero(np.diff(es)) + 1
    for a, b in zip(np.concatenate([[0], cut]), np.concatenate([cut, [len(es)]])):
        idx = order[a:b]
        env = envelopes[es[a]]
        ti = th2[idx] - env_offset[rows_c[idx]][:, None]
        if not env.closed:
            # stay inside [theta_0, theta_K] (round-off of the unfolded angle; outside,
            # the end lines would be extrapolated)
            ti = np.clip(ti, env.theta[0], env.theta[-1])
        out[:, idx] = env.u_derivs(ti, nu)
    return [out[k].reshape(theta.shape) for k in range(nu + 1)]
