"""The envelopes of many stars at once (:mod:`.blend`'s rules in ragged arrays).

Every step (merging collinear edges into super-pieces, the corners' adaptive scales and
certified widths, the knots, the ratio bounds) is one array operation over all stars;
:func:`build_blend` is the one-star view of :func:`build_blend_ragged`.
"""
from __future__ import annotations

import numpy as np

from .blend import CREASE_SCALE, adaptive_scales, fit_blend_widths

__all__ = ["RaggedBlend", "build_blend", "build_blend_ragged"]


def _segments(ptr):
    """(owner (N,), rank (N,)) of a ragged layout with offsets ptr (S+1,): the segment of
    every element and its position within it."""
    counts = np.diff(ptr)
    owner = np.repeat(np.arange(len(counts)), counts)
    return owner, np.arange(int(ptr[-1])) - ptr[:-1][owner]


class RaggedBlend:
    """The blend envelopes of S stars in ragged arrays (result of :func:`build_blend_ragged`).

    ``ok`` (S,): certified (the others need a fallback construction); for those stars
    ``knot_ptr`` (S+1,) offsets into ``knots``, ``line_m`` and ``line_inv`` (the local lines
    u = line_inv cos(theta - line_m)), ``rmin`` / ``rmax`` (S,) the certified bounds of
    R = u~ / u_exact.
    """

    def __init__(self, ok, knot_ptr, knots, line_m, line_inv, rmin, rmax):
        self.ok, self.knot_ptr, self.knots = ok, knot_ptr, knots
        self.line_m, self.line_inv, self.rmin, self.rmax = line_m, line_inv, rmin, rmax


def _fix_end_scales(c, fixed, closed, sptr, kappa):
    """c of the first / last super-piece := max(CREASE_SCALE, kappa) for the open stars whose
    start / end ray is marked in ``fixed`` (S, 2) (crease rays), in place."""
    P = np.diff(sptr)
    fx = np.asarray(fixed, dtype=bool).reshape(-1, 2) & (~closed & (P > 0))[:, None]
    val = max(CREASE_SCALE, kappa)
    c[sptr[:-1][fx[:, 0]]] = val
    c[sptr[1:][fx[:, 1]] - 1] = val


def _real_corners(normal, dist, ptr, closed, span):
    """The corners of S stars where the line changes (collinear pieces run on).

    Returns (pstar, k) per piece (N - S,): its star and index in it, ``real`` (N - S,):
    the corner between piece k-1 and k is a real one (closed stars: for every k, piece
    -1 being K-1 one period back), and ``ok`` (S,): False for closed stars without one."""
    S = len(ptr) - 1
    K = np.diff(ptr) - 1                                  # pieces per star
    pptr = ptr - np.arange(S + 1)                         # piece offsets
    pstar, k = _segments(pptr)                            # star and index of every piece
    is_corner = closed[pstar] | (k >= 1)
    prev = pptr[:-1][pstar] + (k - 1) % K[pstar]
    nprev = normal[prev] - np.where(k == 0, span[pstar], 0.0)
    tau = normal - nprev
    straight = (np.abs(tau) <= 1e-10) & (np.abs(dist - dist[prev]) <= 1e-10 * dist)
    real = is_corner & ~straight
    n_real = np.bincount(pstar[real], minlength=S)
    return pstar, k, real, ~(closed & (n_real == 0))


class _SuperPieces:
    """Maximal runs of collinear pieces (super-pieces) of S stars, in star order.

    ``piece`` the first piece of each, ``star``, ``ptr`` (S+1,) offsets per star, ``count``
    (S,) super-pieces per star, ``j`` the index within its star, ``last``, ``t0`` / ``t1``
    its end angles, ``normal`` / ``dist`` its line. Closed stars start one at every real
    corner; open stars at piece 0 and at every real corner."""

    def __init__(self, theta, normal, dist, ptr, closed, span, pstar, k, real, ok):
        S = len(ptr) - 1
        K = np.diff(ptr) - 1
        start = real | (~closed[pstar] & (k == 0))
        start &= ok[pstar]
        self.piece = sp_piece = np.flatnonzero(start)
        self.star = sstar = pstar[sp_piece]
        self.count = P = np.bincount(sstar, minlength=S)
        self.ptr = sptr = np.concatenate([[0], np.cumsum(P)])
        _, self.j = _segments(sptr)
        self.last = last = self.j == P[sstar] - 1
        nxt = np.where(last, sptr[:-1][sstar], np.arange(len(sp_piece)) + 1)
        k0 = k[sp_piece]
        # end piece index (relative to the star): the next super-piece's start, + K on
        # wrapping
        k1 = np.where(last, np.where(closed[sstar], k[sp_piece[nxt]] + K[sstar], K[sstar]),
                      k[sp_piece[nxt]])
        vbase = ptr[:-1][sstar]
        Ks = K[sstar]
        self.t0 = theta[vbase + k0]
        t1 = theta[vbase + k1 % np.maximum(Ks, 1)] + span[sstar] * (k1 // np.maximum(Ks, 1))
        self.t1 = np.where(~closed[sstar], theta[vbase + np.minimum(k1, Ks)], t1)
        self.normal, self.dist = normal[sp_piece], dist[sp_piece]

    def __len__(self) -> int:
        return len(self.piece)


def _blend_corners(sp, closed, span):
    """The corners to blend: at the start of every super-piece of a closed star, of all but
    the first of an open star. Returns (cj, pj) (the super-piece after / before each
    corner), the lines' normal angles nA, nB relative to the corner, and the rooms
    roomA, roomB each transition may take of its super-pieces (half, or all at an open
    end)."""
    sstar, j, P = sp.star, sp.j, sp.count
    cmask = closed[sstar] | (j >= 1)
    cj = np.flatnonzero(cmask)
    pj = np.where(j[cj] == 0, cj + P[sstar[cj]] - 1, cj - 1)
    ctheta = sp.t0[cj]
    wrap = closed[sstar[cj]] & (j[cj] == 0)
    nA = sp.normal[pj] - np.where(wrap, span[sstar[cj]], 0.0) - ctheta
    nB = sp.normal[cj] - ctheta
    width = sp.t1 - sp.t0
    has_end = closed[sstar] | ~sp.last
    roomA = np.where(cmask[pj], 0.5, 1.0) * width[pj]
    roomB = np.where(has_end[cj], 0.5, 1.0) * width[cj]
    return cj, pj, nA, nB, roomA, roomB


def _knots(sp, c, lo, hi, closed, span, S):
    """Knots lo_0 hi_0 lo_1 hi_1 ... per star (closed: and lo_0 + span, one period on),
    pure stretches of zero length as one knot. Returns (kptr (S+1,), knots, line normal
    angles, line distances c dist, ok (S,): the knots increase strictly)."""
    P, sptr = sp.count, sp.ptr
    n_kn = np.where(P > 0, 2 * P + closed, 0)
    kptr = np.concatenate([[0], np.cumsum(n_kn)])
    kstar, kr = _segments(kptr)
    jj = sptr[:-1][kstar] + np.minimum(kr // 2, np.maximum(P[kstar] - 1, 0))
    extra = kr == 2 * P[kstar]                            # the closing knot
    jj = np.where(extra, sptr[:-1][kstar], jj)
    kn = np.where(extra, lo[jj] + span[kstar], np.where(kr % 2 == 0, lo[jj], hi[jj]))
    mm = np.where(extra, sp.normal[jj] + span[kstar], sp.normal[jj])
    cc = c[jj] * sp.dist[jj]
    dk = np.diff(kn, prepend=np.nan)
    keep = (kr == 0) | (dk > 1e-12 * np.maximum(span[kstar], 1e-300))
    kn, mm, cc, kstar = kn[keep], mm[keep], cc[keep], kstar[keep]
    kptr = np.concatenate([[0], np.cumsum(np.bincount(kstar, minlength=S))])
    _, kr = _segments(kptr)
    inc = np.diff(kn, prepend=np.nan) > 0
    return kptr, kn, mm, cc, np.bincount(kstar[(kr > 0) & ~inc], minlength=S) == 0


def _ratio_bounds(c, sstar, cj, S, kappa):
    """(rmin, rmax) (S,): certified bounds of R = u~ / u_exact: the transitions lie in
    [1, 1/kappa] (closed_form_fit), the pure stretches at 1/c."""
    inv = 1.0 / c
    lo_inv = np.full(S, np.inf)
    hi_inv = np.full(S, -np.inf)
    np.minimum.at(lo_inv, sstar, inv)
    np.maximum.at(hi_inv, sstar, inv)
    has_c = np.bincount(sstar[cj], minlength=S) > 0
    rmin = np.where(has_c, np.minimum(1.0, lo_inv), lo_inv)
    rmax = np.where(has_c, np.maximum(1.0 / kappa, hi_inv), hi_inv)
    return rmin, rmax


def build_blend_ragged(theta, normal, dist, ptr, closed, span, kappa, kernel,
                       fixed=None) -> RaggedBlend:
    """Edge lines (pulled in by c) blended directly across each corner, for S stars at once.

    theta (N,): the stars' polar vertex angles, star i at theta[ptr[i]:ptr[i+1]] (K_i + 1
    vertices, K_i pieces); normal, dist (N - S,): the pieces' lines (star i's pieces at
    ptr[i] - i ...); closed (S,) bool, span (S,). Consecutive collinear pieces are merged
    (super-pieces); every remaining corner gets ONE GERBS transition between its two
    lines, initially half of each adjacent super-piece (the whole of it at an open end),
    narrowed by :func:`fit_blend_widths` until certified. All array operations run over
    all stars at once (no per-star Python work). ``fixed`` (S, 2) bool, optional: open
    stars whose start / end line gets the fixed scale max(CREASE_SCALE, kappa) instead of
    the adaptive one (crease rays: rho~ there then depends on the ray alone).
    """
    theta, normal, dist = (np.asarray(a, dtype=np.float64) for a in (theta, normal, dist))
    ptr = np.asarray(ptr, dtype=np.int64)
    closed = np.asarray(closed, dtype=bool)
    span = np.asarray(span, dtype=np.float64)
    S = len(ptr) - 1
    pstar, k, real, ok = _real_corners(normal, dist, ptr, closed, span)
    sp = _SuperPieces(theta, normal, dist, ptr, closed, span, pstar, k, real, ok)
    cj, pj, nA, nB, roomA, roomB = _blend_corners(sp, closed, span)
    c = adaptive_scales(len(sp), pj, cj, nA, sp.dist[pj], nB, sp.dist[cj], roomA, roomB,
                        kappa, kernel)
    if fixed is not None:
        _fix_end_scales(c, fixed, closed, sp.ptr, kappa)
    wa, wb, cok, _, _ = fit_blend_widths(nA, sp.dist[pj], c[pj], nB, sp.dist[cj], c[cj],
                                         roomA, roomB, kappa, kernel)
    ok &= np.bincount(sp.star[cj][~cok], minlength=S) == 0
    # pure stretch of super-piece j: [t0 + b(corner at its start), t1 - a(corner at its end)]
    bs = np.zeros(len(sp))
    ae = np.zeros(len(sp))
    bs[cj] = wb
    ae[pj] = wa
    kptr, kn, mm, cc, inc = _knots(sp, c, sp.t0 + bs, sp.t1 - ae, closed, span, S)
    ok &= inc
    rmin, rmax = _ratio_bounds(c, sp.star, cj, S, kappa)
    return RaggedBlend(ok, kptr, kn, mm, 1.0 / cc, rmin, rmax)


def build_blend(theta, normal, dist, closed, span, kappa, kernel, fixed=None):
    """:func:`build_blend_ragged` for one star: (knots, m, a, b, Rmin, Rmax) (local lines
    u_j = a_j cos(theta - m_j) + b_j, b = 0; R = u~ / u_exact over everything: rho~/rho in
    [1/Rmax, 1/Rmin]) or None if some corner cannot be certified. fixed: (start, end) bools
    or None (see :func:`build_blend_ragged`)."""
    theta = np.asarray(theta, dtype=np.float64)
    rb = build_blend_ragged(theta, normal, dist, [0, len(theta)], [closed], [span], kappa,
                            kernel, None if fixed is None else [fixed])
    if not rb.ok[0]:
        return None
    a = rb.line_inv
    return rb.knots, rb.line_m, a, np.zeros_like(a), float(rb.rmin[0]), float(rb.rmax[0])
