"""The default smooth star envelope: edge lines blended directly across each corner.

DESIGN section 4; paper eq. (3) (a GERBS spline in the angle) and eq. (62). The
envelope's local functions are the star's edge lines u_e = cos(theta - n_e) / (c_e p_e),
pulled in by c_e in [kappa, 1]; every corner gets ONE GERBS transition between its two
lines, as wide as a rigorous closed-form bound allows (:func:`closed_form_fit`), so
kappa * rho <= rho~ <= rho holds by construction, not by sampling.
:func:`blend_check` is an independent sampled certificate (tests).

:mod:`.blend_ragged` applies these rules to many stars at once.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CONVEX_SCALE", "CREASE_SCALE", "adaptive_scales", "blend_check", "closed_form_fit",
           "fit_blend_widths", "overshoot_profile", "scales_from_corners"]

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
    chunks = ((ea[k], eb[k], nA[k], pA[k], nB[k], pB[k], roomA[k], roomB[k])
              for k in (slice(s, s + _SCALE_CHUNK) for s in range(0, len(nA), _SCALE_CHUNK)))
    return scales_from_corners(n_edges, chunks, kappa, kernel)


def scales_from_corners(n_edges, chunks, kappa, kernel):
    """:func:`adaptive_scales` from the corners in chunks: an iterable of tuples
    (ea, eb, nA, pA, nB, pB, roomA, roomB), each array (m,) (the caller then need not
    hold all corners' arrays at once). The same c to the bit for any chunking."""
    G, GB = overshoot_profile(kernel), overshoot_profile(kernel, mirrored=True)
    hi = np.ones(n_edges)
    lo = np.full(n_edges, kappa)
    # corners in chunks: the ~30 temporaries of a chunk stay in cache (2x at 6e5 corners);
    # min / max are exact, so the per-edge results do not depend on the chunking
    for ea, eb, nA, pA, nB, pB, roomA, roomB in chunks:
        cvx, up, rfx, dn = _corner_wishes(nA, pA, nB, pB, roomA, roomB, kappa, G, GB)
        for e in (ea, eb):
            np.minimum.at(hi, e[cvx], up[cvx])
            np.maximum.at(lo, e[rfx], dn[rfx])
    return np.where(lo <= hi, hi, 0.5 * (lo + hi))


_SCALE_CHUNK = 1 << 16


def _corner_wishes(nA, pA, nB, pB, roomA, roomB, kappa, G, GB):
    """Per corner of :func:`adaptive_scales`: (convex mask, its upper bound of c, reflex
    mask, its lower bound of c)."""
    tau = np.abs(nB - nA)
    convex = (nB - nA) > 0
    straight = tau <= 1e-12
    W = roomA + roomB
    al = roomA / W
    n = len(G) - 1
    gA = _grid_value(G, al, n)
    gB = _grid_value(GB, 1.0 - al, n)
    eA = np.minimum(np.cos(-roomA - nA) ** 2, np.cos(nA) ** 2)
    eB = np.minimum(np.cos(roomB - nB) ** 2, np.cos(nB) ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        st = np.sin(tau)
        need = np.fmax(W * (pA / pB) * st * gA / eA, W * (pB / pA) * st * gB / eB)
    need = np.where(np.isfinite(need), need, np.inf)
    up = np.clip(1.0 - 1.2 * need, max(kappa, CONVEX_SCALE), _C_MAX)
    dn = np.clip(kappa * (1.0 + 1.2 * need), kappa, 1.0)
    return convex & ~straight, up, ~convex & ~straight, dn


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
    allowA, allowB = _allowances(nA, cA, nB, cB, kappa)
    G, GB = overshoot_profile(kernel), overshoot_profile(kernel, mirrored=True)
    n = len(G) - 1
    st = np.sin(tau)
    same = (tau <= 1e-15) & (np.abs(pA - pB) <= 1e-15 * pA)
    a, b = roomA.astype(float).copy(), roomB.astype(float).copy()
    t = np.flatnonzero(~same)
    # the factors that do not change with the widths, once per corner (the same
    # operations as inside the loop, so the same bits): half of the cosines
    rAB, rBA = pA / pB, pB / pA
    cA2, cB2 = np.cos(nA) ** 2, np.cos(nB) ** 2
    # a side's step factor by its test (ok: x 1.0, the same bits): a gather, not np.where's
    # branch per element on a random mask (7-9 % of the fit)
    step = np.array([factor, 1.0])
    for _ in range(iters):
        if not t.size:
            break
        at, bt = a[t], b[t]
        W = at + bt
        al = at / W
        gA = _grid_value(G, al, n)
        gB = _grid_value(GB, 1.0 - al, n)
        eA = np.minimum(np.cos(-at - nA[t]) ** 2, cA2[t])
        eB = np.minimum(np.cos(bt - nB[t]) ** 2, cB2[t])
        stt = st[t]
        okA = W * rAB[t] * stt * gA <= allowA[t] * eA * (1 - 1e-9)
        okB = W * rBA[t] * stt * gB <= allowB[t] * eB * (1 - 1e-9)
        a[t] = at * step.take(okA.view(np.int8))    # (one scatter per side)
        b[t] = bt * step.take(okB.view(np.int8))
        t = t[~(okA & okB)]
    ok = np.ones(len(a), dtype=bool)       # certified: every corner that left the loop
    ok[t] = False
    return a, b, ok


def _allowances(nA, cA, nB, cB, kappa):
    """(allowA, allowB) of :func:`closed_form_fit`: how far R = u~/u_X may move on each
    side, cB (1/max(c) - 1) at a convex corner, cB (1/kappa - 1/min(c)) at a reflex one
    (cA on side B)."""
    cmax, cmin = np.maximum(cA, cB), np.minimum(cA, cB)
    convex = (nB - nA) > 0
    allowA = np.where(convex, cB * (1.0 / cmax - 1.0), cB * (1.0 / kappa - 1.0 / cmin))
    allowB = np.where(convex, cA * (1.0 / cmax - 1.0), cA * (1.0 / kappa - 1.0 / cmin))
    return allowA, allowB


def _grid_index(al, n):
    """ceil(al n) clipped to [0, n] (as np.clip, without its Python-level wrapper)."""
    return np.minimum(np.maximum(np.ceil(al * n).astype(int), 0), n)


def _grid_value(G, al, n):
    """G[_grid_index(al, n)] for G of n + 1 entries: take's clip mode does the clipping
    (the same entries, a NaN's index included, in two passes less)."""
    return G.take(np.ceil(al * n).astype(np.intp), mode="clip")


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
    # rows i, columns j: Fhi_j (w_i - w_j) for j <= i, else 0 (there the product is <= 0,
    # and max(0.0, .) is +0.0 as the masked form's: the same bits, 3x faster)
    D = np.subtract.outer(w, w)
    D *= Fhi
    G = np.maximum(0.0, D, out=D).max(axis=1)
    G.setflags(write=False)
    if len(_G_CACHE) >= 32:     # the oldest goes (a full clear dropped the newest too)
        del _G_CACHE[next(iter(_G_CACHE))]
    _G_CACHE[key] = G
    return G
