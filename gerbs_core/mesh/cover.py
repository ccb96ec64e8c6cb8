"""The star cover of a mesh surface: one smooth size function per vertex (eq. (62)).

psi_v = b(g_v), g_v = r / rho~_v(theta) in v's unfolded polar coordinates, with
rho~_v the smooth GERBS lower envelope (:class:`gerbs_core.gauge.envelope.RadialEnvelope`)
of v's star, the union of its faces. supp psi_v then lies compactly inside the
open star (minimal supports, so B_v = Psi_v, eq. (73)), and psi_v is
C-infinity (ERBS kernels). The star's boundary is the far edges of its faces.

Stars of the same shape up to rotation share one envelope object (also across
surfaces, through a bounded process-wide memo: a rebuild after a settings
change reuses them).
"""
from __future__ import annotations

import numpy as np

__all__ = ["StarCover", "star_cover", "star_boundary", "clear_envelope_cache", "require_cover"]


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
# symmetric meshes repeat star shapes, and a rebuild after a settings change (Blender
# add-on) reuses them. clear_envelope_cache() empties it (benchmarks time cold builds).
_ENVELOPE_CACHE: dict = {}
_ENVELOPE_CACHE_SIZE = 4096


def clear_envelope_cache() -> None:
    """Forget all memoized star envelopes."""
    _ENVELOPE_CACHE.clear()


def build_envelopes(topo, charts, corners2d, kappa=0.8, shrink=0.95,
                    exact=False, kernel=None, fixed_ends=None):
    """Smooth star envelopes (:class:`gerbs_core.gauge.envelope.RadialEnvelope`) of all charts.

    Returns (envelopes (list), corner_envelope (C,) int, corner_offset (C,)): the
    envelope serving each corner's sector, evaluated at theta - corner_offset.
    One closed envelope per interior vertex, one open envelope per boundary
    fan (a function of the unfolded angle; only the chart angle is compressed).
    Stars of the same shape up to rotation share one object. fixed_ends (V, 2) bool,
    optional: boundary fans whose start / end ray is a crease (fixed end-line scales).
    """
    from ..gauge.envelope import RadialEnvelope
    index, keys = {}, []          # key -> envelope number; the keys in order
    corner_env = np.full(topo.n_corners, -1, dtype=np.int64)
    env_offset = np.zeros(topo.n_corners)
    so = topo.star_offsets
    th_l, r_l, sig = far_corner_polar(topo, charts, corners2d)
    settings = (float(kappa), float(shrink), bool(exact), kernel)
    todo = {}                     # key -> (theta, radius) of the stars not memoized

    def get(sigs, closed, make, fixed=(False, False)):
        key = (closed, settings, tuple(sigs)) + ((fixed,) if any(fixed) else ())
        j = index.get(key)
        if j is None:
            if key not in _ENVELOPE_CACHE:
                th, r = make()
                todo[key] = (th - th[0], r, fixed)
            j = index[key] = len(keys)
            keys.append(key)
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
        fx = (False, False) if fixed_ends is None else tuple(bool(b) for b in fixed_ends[v])
        e = get(sigs, False, lambda: chain(star), fx)
        corner_env[star] = e
        env_offset[star] = th_l[star[0]][0]
    # the new star shapes in one batch (the corner fits vectorized over all of them)
    made = RadialEnvelope.many([t[:2] for t in todo.values()], [k[0] for k in todo],
                               kappa=kappa, shrink=shrink, kernel=kernel, exact=exact,
                               fixed_ends=[t[2] for t in todo.values()])
    fresh = dict(zip(todo, made))
    envs = [fresh[k] if k in fresh else _ENVELOPE_CACHE[k] for k in keys]
    for key, env in fresh.items():
        if len(_ENVELOPE_CACHE) >= _ENVELOPE_CACHE_SIZE:
            _ENVELOPE_CACHE.pop(next(iter(_ENVELOPE_CACHE)))
        _ENVELOPE_CACHE[key] = env
    return envs, corner_env, env_offset


def eval_envelopes(table, corner_env, env_offset, corners: np.ndarray, theta: np.ndarray,
                   nu: int):
    """[u~, u~', u~''] (up to nu), u~ = 1/rho~, of the envelope serving each corner.

    table: :class:`gerbs_core.gauge.envelope.EnvelopeTable` of the cover's envelopes;
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

    ``envelopes`` (list of RadialEnvelope) and ``table`` (the same packed for vectorized
    evaluation), ``corner_env`` (C,) the envelope serving each corner's sector,
    ``env_offset`` (C,) its angle offset, ``kernel`` the GERBS kernel of the bumps.
    """

    def __init__(self, envelopes, corner_env, env_offset, kernel):
        from ..gauge.envelope import EnvelopeTable
        self.envelopes = tuple(envelopes)
        self.table = EnvelopeTable(self.envelopes)
        corner_env.flags.writeable = False
        env_offset.flags.writeable = False
        self.corner_env, self.env_offset, self.kernel = corner_env, env_offset, kernel

    def reciprocal_radius(self, corners, theta, nu: int):
        """[u~, u~', u~''] (u~ = 1 / rho~) of each corner's envelope at unfolded angles theta."""
        return eval_envelopes(self.table, self.corner_env, self.env_offset, corners, theta, nu)

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
    (V, 2): see :func:`build_envelopes`."""
    envs, ce, eo = build_envelopes(topo, charts, corners2d, kappa=kappa, shrink=shrink,
                                   exact=exact, kernel=kernel, fixed_ends=fixed_ends)
    return StarCover(envs, ce, eo, kernel)
