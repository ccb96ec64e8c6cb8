"""The default smooth star envelope: edge lines blended directly across each corner.

DESIGN section 4; paper eq. (3) (a GERBS spline in the angle) and eq. (62). The
envelope's local functions are the star's edge lines u_e = cos(theta - n_e) / (c_e p_e),
pulled in by c_e in [kappa, 1]; every corner gets ONE GERBS transition between its two
lines, as wide as a rigorous closed-form bound allows (:func:`closed_form_fit`), so
kappa * rho <= rho~ <= rho holds by construction, not by sampling.
:func:`blend_check` is an independent sampled certificate (tests).

:func:`build_blend_ragged` builds the envelopes of many stars at once, in ragged arrays:
every step (merging collinear edges, the corners' scales and certified widths, the knots)
is one array operation over all stars.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CONVEX_SCALE", "CREASE_SCALE", "adaptive_scales", "blend_check", "closed_form_fit",
           "fit_blend_widths", "overshoot_profile", "build_blend", "build_blend_ragged",
           "RaggedBlend"]

_BLEND_SAMPLES = 24       # sub-intervals per side in blend_check
_BLEND_SHRINK = 0.85      # factor applied to a failing side's width


CONVEX_SCALE = 0.9        # c of a line next to a convex corner (adaptive: the floor)


_C_MAX = 0.97             # adaptive c of a convex-cornered line stays <= this

# c of the end lines of an open star whose end ray is a cut crease
# (:mod:`gerbs_core.mesh.creases`): fixed, so that the two sides of the crease see the same
# rho~ = shrink c |ab| on it (the adaptive c depends on the far edges of each side)
CREASE_SCALE = CONVEX_SCALE


def adaptive_scales(n_edges, ea, eb, nA, pA, nB, pB, roomA, roomB, kappa, kernel):
    """Per edge line the scale c as close to 1 as its corners allow while their
    transitions can still fill the whole room (bigger supports, thicker cover).

    Corner (edges ea -> eb): the closed-form bound of :func:`closed_form_fit`
    at the full room needs the allowance need = W D G on each side; a convex
    corner then wants c <= 1 - need (allowance 1 - c), a reflex one
    c >= kappa (1 + need) (allowance c / kappa - 1). Each edge takes the
    tightest of its corners' wishes; next to a convex corner c stays in
    [CONVEX_SCALE, _C_MAX] (below 0.9 the supports shrink and the partition
    steepens more than the wider transitions gain: measured), conflicting
    wishes: halfway. Only the quality depends on this choice; the widths are
    then certified for it (:func:`fit_blend_widths`).
    """
    tau = np.abs(nB - nA)
    convex = (nB - nA) > 0
    straight = tau <= 1e-12
    W = roomA + roomB
    al = roomA / W
    G, GB = overshoot_profile(kernel), overshoot_profile(kernel, mirrored=True)
    n = len(G) - 1
    gA = G[np.clip(np.ceil(al * n).astype(int), 0, n)]
    gB = GB[np.clip(np.ceil((1.0 - al) * n).astype(int), 0, n)]
    eA = np.minimum(np.cos(-roomA - nA) ** 2, np.cos(nA) ** 2)
    eB = np.minimum(np.cos(roomB - nB) ** 2, np.cos(nB) ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        need = np.fmax(W * (pA / pB) * np.sin(tau) * gA / eA,
                       W * (pB / pA) * np.sin(tau) * gB / eB)
    need = np.where(np.isfinite(need), need, np.inf)
    hi = np.ones(n_edges)
    lo = np.full(n_edges, kappa)
    cvx = convex & ~straight
    rfx = ~convex & ~straight
    up = np.clip(1.0 - 1.2 * need, max(kappa, CONVEX_SCALE), _C_MAX)
    dn = np.clip(kappa * (1.0 + 1.2 * need), kappa, 1.0)
    for e in (ea, eb):
        np.minimum.at(hi, e[cvx], up[cvx])
        np.maximum.at(lo, e[rfx], dn[rfx])
    return np.where(lo <= hi, hi, 0.5 * (lo + hi))


def blend_check(nA, pA, cA, nB, pB, cB, a, b, kappa, kernel, samples=_BLEND_SAMPLES,
                chunk=1024):
    """Certify the corner transitions u~ = (1 - F(w)) uA / cA + F(w) uB / cB.

    Angles relative to the corner ray (at 0); line X: uX = cos(x - nX) / pX; the
    transition runs over [-a, b] (w = (x + a) / (a + b)), the exact radius is
    line A for x < 0 and line B for x > 0. Arrays (n,). Rigorous: on each of
    ``samples`` sub-intervals per side F lies between its end values (F is
    increasing) and the ratio of the two lines is monotone, and the normalised
    blend R = u~ / u_exact is bilinear in (F, ratio): its extremes over the
    sub-interval are among the four corner values. Returns (okA, okB, Rmin, Rmax)
    with ok: kappa * rho <= rho~ <= rho (1 <= R <= 1/kappa) on that side.
    Works in chunks of ``chunk`` corners (the temporaries then stay in cache).
    """
    if len(a) > chunk:
        parts = [blend_check(nA[k:k + chunk], pA[k:k + chunk], cA[k:k + chunk],
                             nB[k:k + chunk], pB[k:k + chunk], cB[k:k + chunk],
                             a[k:k + chunk], b[k:k + chunk], kappa, kernel, samples, chunk)
                 for k in range(0, len(a), chunk)]
        return tuple(np.concatenate(z) for z in zip(*parts))
    m = samples
    i = np.arange(m + 1) / m
    # x from -a to b: left half -a (1 - i), right half b i (the corner shared)
    x = np.concatenate([-a[:, None] * (1.0 - i), b[:, None] * i[1:]], axis=1)
    w = np.clip((x + a[:, None]) / (a + b)[:, None], 0.0, 1.0)
    F = kernel.cdf_derivs(w.ravel(), 0)[0].reshape(w.shape)
    uA = np.cos(x - nA[:, None]) * (1.0 / pA)[:, None]
    uB = np.cos(x - nB[:, None]) * (1.0 / pB)[:, None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # side A: R = (1 - F) kA + F (uB/uA) kB; side B: R = F kB + (1 - F) (uA/uB) kA
        own = np.concatenate([1.0 - F[:, :m + 1], F[:, m:]], axis=1)
        r = np.concatenate([uB[:, :m + 1] / uA[:, :m + 1], uA[:, m:] / uB[:, m:]], axis=1)
    kA, kB = (1.0 / cA)[:, None], (1.0 / cB)[:, None]
    k0 = np.concatenate([np.broadcast_to(kA, (len(a), m + 1)),
                         np.broadcast_to(kB, (len(a), m + 1))], axis=1)
    k1 = np.concatenate([np.broadcast_to(kB, (len(a), m + 1)),
                         np.broadcast_to(kA, (len(a), m + 1))], axis=1)
    # sub-intervals: j = 0..m-1 (side A), m+1..2m (side B); on each the own weight lies
    # between its end values, r between its end values (monotone), R bilinear
    lo = hi = None
    with np.errstate(invalid="ignore", over="ignore"):
        for Fw in (own[:, :-1], own[:, 1:]):
            for rr, kk0, kk1 in ((r[:, :-1], k0[:, :-1], k1[:, :-1]),
                                 (r[:, 1:], k0[:, 1:], k1[:, 1:])):
                v = Fw * kk0 + (1.0 - Fw) * rr * kk1
                lo = v if lo is None else np.fmin(lo, v)
                hi = v if hi is None else np.fmax(hi, v)
    bad = ~(np.isfinite(r[:, :-1]) & np.isfinite(r[:, 1:]))
    # drop the pseudo sub-interval m (it straddles the corner: side A's last point
    # with side B's first point, both at x = 0, mixed formulas)
    lo = np.where(bad, -np.inf, lo)
    hi = np.where(bad, np.inf, hi)
    loA, hiA = lo[:, :m].min(axis=1), hi[:, :m].max(axis=1)
    loB, hiB = lo[:, m + 1:].min(axis=1), hi[:, m + 1:].max(axis=1)
    top = (1.0 + 1e-12) / kappa
    okA = (loA >= 1.0 - 1e-12) & (hiA <= top)
    okB = (loB >= 1.0 - 1e-12) & (hiB <= top)
    return okA, okB, np.fmin(loA, loB), np.fmax(hiA, hiB)


def closed_form_fit(nA, pA, cA, nB, pB, cB, roomA, roomB, kappa, kernel, factor, iters=200):
    """Certified transition widths from a closed-form bound (no sampling).

    On side A (x in [-a, 0], corner ray at 0) the exact radius is line A and
    R = u~/u_A = (1 - F)/cA + F r/cB with r = uB/uA. r(0) = 1 and
    |r'(x)| = (pA/pB) |sin(nB - nA)| / cos^2(x - nA) <= D_A(a) (the max of
    1/cos^2 over [-a, 0] is at an end), so |r - 1| <= D_A |x| and R stays in
    [1, 1/kappa] if F(w) D_A |x| <= allowance_A: convex corner (r <= 1)
    cB (1/max(c) - 1), reflex (r >= 1) cB (1/kappa - 1/min(c)). With the corner
    at alpha = a / (a + b) of a transition of width W = a + b, F(w)|x| <=
    W G(alpha) (:func:`overshoot_profile`), so W D_A(a) G(alpha) <= allowance_A
    suffices; likewise on side B with G_B(1 - alpha) (the profile of the mirrored
    kernel 1 - F(1 - w): F need not be symmetric, e.g. ERBS with lam != 1/2). Each side is shrunk by
    ``factor`` while its own condition fails (O(1) per corner and pass).
    Returns (a, b, ok)."""
    tau = np.abs(nB - nA)
    cmax, cmin = np.maximum(cA, cB), np.minimum(cA, cB)
    convex = (nB - nA) > 0
    allowA = np.where(convex, cB * (1.0 / cmax - 1.0), cB * (1.0 / kappa - 1.0 / cmin))
    allowB = np.where(convex, cA * (1.0 / cmax - 1.0), cA * (1.0 / kappa - 1.0 / cmin))
    G, GB = overshoot_profile(kernel), overshoot_profile(kernel, mirrored=True)
    n = len(G) - 1
    st = np.sin(tau)
    same = (tau <= 1e-15) & (np.abs(pA - pB) <= 1e-15 * pA)
    a, b = roomA.astype(float).copy(), roomB.astype(float).copy()
    ok = same.copy()
    t = np.flatnonzero(~same)
    for _ in range(iters):
        if not t.size:
            break
        W = a[t] + b[t]
        al = a[t] / W
        gA = G[np.clip(np.ceil(al * n).astype(int), 0, n)]
        gB = GB[np.clip(np.ceil((1.0 - al) * n).astype(int), 0, n)]
        eA = np.minimum(np.cos(-a[t] - nA[t]) ** 2, np.cos(nA[t]) ** 2)
        eB = np.minimum(np.cos(b[t] - nB[t]) ** 2, np.cos(nB[t]) ** 2)
        okA = W * (pA[t] / pB[t]) * st[t] * gA <= allowA[t] * eA * (1 - 1e-9)
        okB = W * (pB[t] / pA[t]) * st[t] * gB <= allowB[t] * eB * (1 - 1e-9)
        good = okA & okB
        ok[t[good]] = True
        a[t[~okA]] *= factor
        b[t[~okB]] *= factor
        t = t[~good]
    return a, b, ok


def fit_blend_widths(nA, pA, cA, nB, pB, cB, a, b, kappa, kernel, factor=_BLEND_SHRINK):
    """Certified transition widths a (into A) and b (into B), at most the rooms:
    :func:`closed_form_fit` (rigorous bound, O(1) per corner and pass). Returns
    (a, b, ok, Rmin, Rmax), R = u~ / u_exact certified in [Rmin, Rmax] = [1, 1/kappa].

    (A search widening them with the sampled bound :func:`blend_check` from up to
    twice these widths was tried: same measured smoothness on the test meshes and
    covers, 2-3x the cost; blend_check remains an independent check in the tests.)
    """
    a0, b0 = np.asarray(a, float), np.asarray(b, float)
    fa, fb, ok = closed_form_fit(nA, pA, cA, nB, pB, cB, a0, b0, kappa, kernel, factor)
    return fa, fb, ok, np.ones(len(a0)), np.full(len(a0), 1.0 / kappa)


_G_CACHE: dict = {}


def overshoot_profile(kernel, n=513, mirrored=False):
    """G(alpha) on the grid alpha = k/(n-1), an upper bound of
    max over w in [0, alpha] of F(w) (alpha - w): the worst weight times distance
    on side A of a unit-width transition whose corner sits at w = alpha.
    mirrored=True: the same for the mirrored kernel 1 - F(1 - w), i.e. side B
    (weight 1 - F(w) at distance w - alpha), used as G_B(1 - alpha); equal to G
    only for symmetric kernels (ERBS with lam = 1/2, LogisticStep). Between grid
    points F(w)(alpha - w) <= F(w_hi)(alpha - w_lo) (F increasing): rigorous.
    Memoized by the kernel's value (kernels are immutable value objects; a kernel
    whose parameters do not hash is keyed by its values on the grid)."""
    try:
        key = (kernel, n, mirrored)
        G = _G_CACHE.get(key)
    except TypeError:
        key, G = None, None
    if G is not None:
        return G
    w = np.linspace(0.0, 1.0, n)
    F = kernel.cdf_derivs(w, 0)[0]
    if mirrored:  # grid symmetric: 1 - w_k = w_(n-1-k)
        F = 1.0 - F[::-1]
    if key is None:
        key = F.tobytes()
        G = _G_CACHE.get(key)
        if G is not None:
            return G
    Fhi = np.append(F[1:], 1.0)
    G = np.max(np.where(w[None, :] <= w[:, None], Fhi[None, :] * (w[:, None] - w[None, :]),
                        0.0), axis=1)
    G.setflags(write=False)
    if len(_G_CACHE) > 32:
        _G_CACHE.clear()
    _G_CACHE[key] = G
    return G


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
