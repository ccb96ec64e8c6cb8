"""The star cover of a mesh surface: one smooth size function per vertex (eq. (62)).

psi_v = b(g_v), g_v = r / rho~_v(theta) in v's unfolded polar coordinates, with
rho~_v the smooth GERBS lower envelope (:class:`gerbs_core.gauge.envelope.RadialEnvelope`)
of v's star, the union of its faces. supp psi_v then lies compactly inside the
open star (minimal supports, so B_v = Psi_v, eq. (73)), and psi_v is
C-infinity (ERBS kernels). The star's boundary is the far edges of its faces.

Stars of the same shape up to rotation share one envelope; all envelopes are built in
one vectorized pass (:func:`gerbs_core.gauge.envelope_table.envelope_table`).
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from .arrays import unique_rows

__all__ = ["StarCover", "star_cover", "star_boundary", "require_cover"]


def require_cover(eps: float, kernel) -> None:
    """Refuse a cover with holes (eps = min max_v psi_v = 0 at some sample): there
    Psi = psi / sum psi is 0/0. Happens for kernels whose 1 - F(t) underflows well
    before t = 1 (e.g. ERBS(gamma=7.389, lam=0, sigma=0))."""
    from ..errors import InvalidParameterError
    if not eps > 0.0:
        raise InvalidParameterError(
            "kernel", f"{kernel!r} leaves holes in the cover: every size function "
            f"psi_v = 1 - F(g_v) is 0 at some samples (1 - F(t) underflows for t < 1); "
            f"use a kernel whose F reaches 1 only near t = 1")

def _sector_boundary(topo, charts, corners2d: np.ndarray, c: int):
    """Polar (theta, r) of the far corners next(c) ... prev(c) of corner c's face, in order."""
    off = topo.face_offsets
    f = topo.corner_face[c]
    n = off[f + 1] - off[f]
    k = c - off[f]
    far = off[f] + (k + 1 + np.arange(n - 1)) % n
    r, t = charts.unfolded(np.full(len(far), c), corners2d[far])
    return t, r


def star_boundary(topo, charts, corners2d: np.ndarray, v: int, first=0, last=None):
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


def far_corner_polar(topo, charts, corners2d):
    """Per corner c: unfolded polar (theta, r) of its face's corners next(c) ... prev(c).

    Returns (theta (C, W), r (C, W), count (C,), shape (C,)): the n - 1 far corners of
    c's n-gon in the first count[c] = n - 1 columns (W = n_max - 1; padding 0), one
    vectorized call per face size, and equal shape ids for congruent sectors (angles
    relative to the sector's start and radii equal to 1e-11).
    """
    sizes, cf, off = topo.face_sizes, topo.corner_face, topo.face_offsets
    W = int(sizes.max()) - 1
    C = topo.n_corners
    th = np.zeros((C, W))
    rr = np.zeros((C, W))
    count = sizes[cf] - 1
    for n in np.unique(sizes).tolist():
        cs = np.flatnonzero(sizes[cf] == n)
        k = cs - off[cf[cs]]
        idx = off[cf[cs]][:, None] + (k[:, None] + 1 + np.arange(n - 1)[None, :]) % n
        r, t = charts.unfolded(np.broadcast_to(cs[:, None], idx.shape), corners2d[idx])
        th[cs, :n - 1], rr[cs, :n - 1] = t, r
    key = np.round(np.concatenate([count[:, None], th - th[:, :1], rr], axis=1), 11)
    key[:, 1:W + 1] = np.where(np.arange(W) < count[:, None], key[:, 1:W + 1], 0.0)
    shape = unique_rows(key)[1]
    return th, rr, count, shape.reshape(-1)


def _canonical_rotation(seq):
    """Per row of seq (n, k) the rotation j whose sequence seq[j:] + seq[:j] is
    lexicographically smallest (the first such j): rotated copies of a star shape then
    read the same."""
    n, k = seq.shape
    rot = (np.arange(k)[:, None] + np.arange(k)[None, :]) % k            # (k, k)
    R = seq[:, rot]                                                       # (n, k, k)
    alive = np.ones((n, k), dtype=bool)
    big = np.iinfo(np.int64).max
    for t in range(k):
        col = np.where(alive, R[:, :, t], big)
        alive &= col == col.min(axis=1, keepdims=True)
    return np.argmax(alive, axis=1)


def build_envelopes(topo, charts, corners2d, kappa=0.8, shrink=0.95, exact=False,
                    kernel=None, fixed_ends=None):
    """Smooth envelopes of all vertex stars, in one
    :class:`~gerbs_core.gauge.envelope_table.EnvelopeTable`.

    Returns (table, corner_envelope (C,) int, corner_offset (C,)): the envelope serving
    each corner's sector, evaluated at theta - corner_offset. One closed envelope per
    interior vertex, one open envelope per boundary fan (a function of the unfolded angle;
    only the chart angle is compressed). Stars of the same shape up to rotation share one
    envelope. Array operations over all stars (grouped by valence), no per-vertex work.
    fixed_ends (V, 2) bool, optional: boundary fans whose start / end ray is a cut crease
    (fixed end-line scales, :func:`gerbs_core.gauge.blend_ragged.build_blend_ragged`); they share
    envelopes only with fans of the same shape and the same flags.
    """
    from ..gauge.envelope_table import envelope_table
    so = np.asarray(topo.star_offsets, dtype=np.int64)
    sc = np.asarray(topo.star_corners, dtype=np.int64)
    th, rr, count, shape = far_corner_polar(topo, charts, corners2d)
    val = np.diff(so)
    closed_v = ~np.asarray(charts.boundary, dtype=bool)
    corner_env = np.full(topo.n_corners, -1, dtype=np.int64)
    env_offset = np.zeros(topo.n_corners)
    fixed = None if fixed_ends is None else np.asarray(fixed_ends, dtype=bool).reshape(-1, 2)
    reps, rep_closed, rep_fixed = [], [], []     # per group: the representative stars
    n_env = 0
    for k in np.unique(val[val > 0]).tolist():
        for cl in (True, False):
            vs = np.flatnonzero((val == k) & (closed_v == cl))
            if not len(vs):
                continue
            stars = sc[so[vs][:, None] + np.arange(k)[None, :]]          # (n, k) corners
            if cl:
                j = _canonical_rotation(shape[stars])
                stars = stars[np.arange(len(vs))[:, None], (j[:, None] + np.arange(k)) % k]
            key = shape[stars]
            if fixed is not None and not cl:
                key = np.column_stack([key, fixed[vs, 0] + 2 * fixed[vs, 1]])
            first, inv = unique_rows(key)
            corner_env[stars] = (n_env + inv.reshape(-1))[:, None]
            start = charts.theta0[stars[:, 0]] if cl else th[stars[:, 0], 0]
            env_offset[stars] = start[:, None]
            reps.append(stars[first])
            rep_closed.append(cl)
            rep_fixed.append(np.zeros((len(first), 2), bool) if fixed is None or cl
                             else fixed[vs[first]])
            n_env += len(first)
    theta, radius, ptr, closed = _chains(reps, rep_closed, th, rr, count, charts)
    table = envelope_table(theta, radius, ptr, closed, kappa=kappa, shrink=shrink,
                           kernel=kernel, exact=exact,
                           fixed=None if fixed is None else np.concatenate(rep_fixed))
    return table, corner_env, env_offset


def _chains(reps, rep_closed, th, rr, count, charts):
    """Ragged polar vertex lists (theta, radius, ptr, closed) of the representative stars:
    each corner's far corners but its last (the next sector's first), then the closing
    vertex (closed: the first again at theta = span; open: the last corner's last far
    corner). Angles start at 0 (closed: from the first sector's start, wrapped)."""
    th_all, r_all, closed_all, ptr = [], [], [], [0]
    W = th.shape[1]
    for stars, cl in zip(reps, rep_closed):
        n = len(stars)
        use = (np.arange(W)[None, None, :] < (count[stars] - 1)[..., None]).reshape(n, -1)
        t = th[stars]                                                       # (n, k, W)
        if cl:
            T = charts.span[charts.corner_vertex[stars[:, 0]]]
            t = t - charts.theta0[stars[:, 0]][:, None, None]
            t = np.where(t < -1e-9 * T[:, None, None], t + T[:, None, None], t)  # the seam
            end_t, end_r = T, rr[stars[:, 0], 0]
        else:
            last = stars[:, -1]
            end_t, end_r = th[last, count[last] - 1], rr[last, count[last] - 1]
        per = use.sum(axis=1) + 1
        starts = np.concatenate([[0], np.cumsum(per)[:-1]])
        body = np.ones(int(per.sum()), dtype=bool)
        body[starts + per - 1] = False
        tt = np.empty(len(body))
        rv = np.empty(len(body))
        tt[body], rv[body] = t.reshape(n, -1)[use], rr[stars].reshape(n, -1)[use]
        tt[~body], rv[~body] = end_t, end_r
        if cl:
            tt[starts] = 0.0
        else:
            tt -= np.repeat(tt[starts], per)
        th_all.append(tt)
        r_all.append(rv)
        closed_all.append(np.full(n, cl))
        ptr.extend((ptr[-1] + np.cumsum(per)).tolist())
    return (np.concatenate(th_all), np.concatenate(r_all), np.array(ptr, dtype=np.int64),
            np.concatenate(closed_all))


def eval_envelopes(table, corner_env, env_offset, corners: np.ndarray, theta: np.ndarray,
                   nu: int):
    """[u~, u~', u~''] (up to nu), u~ = 1/rho~, of the envelope serving each corner.

    table: :class:`gerbs_core.gauge.envelope_table.EnvelopeTable` of the cover's envelopes;
    theta (..., P): unfolded angles (chart of the corner's vertex); corners either of
    theta's shape, or broadcastable against it, or of shape theta.shape[:-1] (one corner
    per row of P samples).
    """
    theta = np.asarray(theta, dtype=np.float64)
    corners = np.asarray(corners)
    if corners.ndim and corners.shape == theta.shape[:-1]:
        corners = corners[..., None]        # one corner per row of samples
    u = table.u_derivs(corner_env[corners], theta - env_offset[corners], nu)
    return [u[k] for k in range(nu + 1)]


class StarCover:
    """The size functions psi_v of all vertices (immutable).

    ``table`` (:class:`~gerbs_core.gauge.envelope_table.EnvelopeTable`): the star envelopes;
    ``envelopes`` the same as :class:`~gerbs_core.gauge.envelope.RadialEnvelope` objects
    (made on first use); ``corner_env`` (C,) the envelope serving each corner's sector,
    ``env_offset`` (C,) its angle offset, ``kernel`` the GERBS kernel of the bumps.
    """

    def __init__(self, table, corner_env, env_offset, kernel, caps=None):
        self.table, self.caps = table, caps       # caps: spoke_caps.SpokeCaps or None
        corner_env.flags.writeable = False
        env_offset.flags.writeable = False
        self.corner_env, self.env_offset, self.kernel = corner_env, env_offset, kernel

    @cached_property
    def envelopes(self) -> tuple:
        return tuple(self.table.envelope(i) for i in range(len(self.table)))

    def reciprocal_radius(self, corners, theta, nu: int):
        """[u~, u~', u~''] (u~ = 1 / rho~) of each corner's envelope at unfolded angles theta."""
        u = eval_envelopes(self.table, self.corner_env, self.env_offset, corners, theta, nu)
        return u if self.caps is None else self.caps.apply(u, corners, theta, nu)

    def psi_jet(self, charts, corners, x, nu: int, pol=None):
        """Jet of psi_v = b(r u~(theta)) at face points x (..., 2) of the corners' faces
        (corners broadcastable against x[..., 0]); also returns the polar jet used."""
        from ..gauge.jet import bump_jet, star_gauge_jet
        if pol is None or len(pol) < nu + 1:
            pol = charts.polar(corners, x, nu)
        r_jet = [p[0] for p in pol]
        t_jet = [p[1] for p in pol]
        u = self.reciprocal_radius(corners, t_jet[0], nu)
        return bump_jet(self.kernel, star_gauge_jet(r_jet, t_jet, u, nu), nu), pol


def star_cover(topo, charts, corners2d, kernel, kappa=0.8, shrink=0.95, exact=False,
               fixed_ends=None) -> StarCover:
    """The star cover of a mesh with face layouts corners2d (see the module docstring).
    ``exact``: the exact (kinked) star radius instead of the smooth envelope -- a
    deliberately non-smooth variant, the control of the smoothness tests. ``fixed_ends``
    (V, 2): see :func:`build_envelopes`. Envelope spikes at sliver fans are capped
    (:mod:`gerbs_core.mesh.spoke_caps`; not with ``exact``)."""
    table, ce, eo = build_envelopes(topo, charts, corners2d, kappa=kappa, shrink=shrink,
                                    exact=exact, kernel=kernel, fixed_ends=fixed_ends)
    cover = StarCover(table, ce, eo, kernel)
    if exact:
        return cover
    from .spoke_caps import spoke_caps
    caps = spoke_caps(topo, charts, corners2d, lambda c, t: cover.reciprocal_radius(c, t, 0)[0],
                      kernel)
    return cover if caps is None else StarCover(table, ce, eo, kernel, caps)
