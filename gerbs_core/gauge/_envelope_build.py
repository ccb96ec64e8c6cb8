"""Knots and local functions of the smooth radial envelope (DESIGN section 4).

``build_blend`` (the default, see its docstring and :func:`blend_check`): the
edge lines pulled in by c in [kappa, 1], one wide GERBS transition per corner.
Two older certified constructions (fallbacks) of rho~ = 1/u~, u~ = sum_j G_j u_j with local
functions u_j(theta) = a_j cos(theta - m_j) + b_j (a straight line: b = 0,
a = 1/q; a constant radius c: a = 0, b = 1/c):

* ``fillet``: exact edge lines away from the corners; each corner is rounded
  by an arc inscribed in it (convex: chords of the arc as local lines;
  reflex: tangents of an arc tangent to the lines scaled by (1+kappa)/2),
  arc size halved until certified. Zero curvature along the edges.
* ``constant``: DESIGN's rule -- knots at the corners, intervals bisected
  while min rho / max rho < sqrt(kappa), constant coefficient at a knot =
  min of rho over the two intervals beside it. Better on slivers (the
  rounding of a fillet must fit inside the sliver).

Both guarantee kappa * rho <= 1/u_j <= rho on the knot intervals where u_j
is used, hence (convex combination) kappa * rho <= rho~ <= rho;
:func:`interval_ratios` certifies it numerically at the only places where
the ratio can be extremal.
"""
from __future__ import annotations

import math

import numpy as np

_MAX_HALVINGS = 60


def line_through(px, py, qx, qy):
    """(m, q) of the line through two points (counter-clockwise, origin inside)."""
    ex, ey = qx - px, qy - py
    length = np.hypot(ex, ey)
    with np.errstate(divide="ignore", invalid="ignore"):   # coincident points -> nan,
        nx, ny = ey / length, -ex / length      # rejected by the certification
    # (outward normal of p -> q, counter-clockwise)
    return np.arctan2(ny, nx), px * nx + py * ny


_line_through = line_through


def interval_ratios(knots, m, a, b, theta, normal, dist, period):
    """(local radius)/rho where it can be extremal, for every knot interval.

    Sub-intervals between knots and corners each lie in one piece k and one
    knot interval [t_j, t_j+1]; for both local functions the ratio
    u_k / u_j is monotone (two lines) or extremal at theta = n_k (a
    constant over p/cos): checked at the sub-interval's ends and at n_k.
    Lines that miss a ray give +inf (flagged as > 1). Returns a flat array.
    """
    th, nrm, dst = theta, normal, dist
    if period is not None:   # knots run one period from the first knot
        th = np.concatenate([theta - period, theta[1:], theta[1:] + period])
        nrm = np.concatenate([normal - period, normal, normal + period])
        dst = np.concatenate([dist, dist, dist])
    inner = th[(th > knots[0]) & (th < knots[-1])]
    x = np.union1d(knots, inner)
    x0, x1 = x[:-1], x[1:]
    mid = 0.5 * (x0 + x1)
    j = np.clip(np.searchsorted(knots, mid, side="right") - 1, 0, len(knots) - 2)
    k = np.clip(np.searchsorted(th, mid, side="right") - 1, 0, len(dst) - 1)
    nk, pk = nrm[k], dst[k]
    foot = np.clip(nk, x0, x1)
    out = []
    for jj in (j, j + 1):
        for xx in (x0, x1, foot):
            uk = np.cos(xx - nk) / pk
            uj = a[jj] * np.cos(xx - m[jj]) + b[jj]
            with np.errstate(divide="ignore", invalid="ignore"):
                out.append(np.where(uj > 0, uk / uj, np.inf))
    return np.concatenate(out)


def _min_max(n, p, a, b):
    """Exact min and max of p / cos(theta - n) over [a, b] (|theta - n| < pi/2)."""
    ra, rb = p / math.cos(a - n), p / math.cos(b - n)
    return (p if a < n < b else min(ra, rb)), max(ra, rb)


def build_constant(theta, normal, dist, closed, kappa):
    """DESIGN's constant-coefficient envelope: (knots, m, a, b)."""
    K = len(dist)
    cuts = [[theta[k], theta[k + 1]] for k in range(K)]
    for k in range(K):
        for _ in range(_MAX_HALVINGS):
            t = cuts[k]
            new = [t[0]]
            for x0, x1 in zip(t[:-1], t[1:]):
                lo, hi = _min_max(normal[k], dist[k], x0, x1)
                if lo < math.sqrt(kappa) * hi:
                    new.append(0.5 * (x0 + x1))
                new.append(x1)
            if len(new) == len(t):
                break
            cuts[k] = new
    knots, lows = [], []
    for k in range(K):
        t = cuts[k]
        knots.extend(t[:-1])
        lows.extend(_min_max(normal[k], dist[k], x0, x1)[0] for x0, x1 in zip(t[:-1], t[1:]))
    knots.append(theta[-1])
    lows = np.array(lows)
    if closed:
        c = np.minimum(np.append(lows[-1], lows), np.append(lows, lows[0]))
    else:
        c = np.minimum(np.append(lows[0], lows), np.append(lows, lows[-1]))
    return np.array(knots), np.zeros_like(c), np.zeros_like(c), 1.0 / c


def build_fillet(theta, radius, normal, dist, closed, span, kappa):
    """Exact edge lines + rounded corners: (knots, m, a, b) or None if a
    corner cannot be rounded within its room."""
    th, K, T = theta, len(dist), span
    n, p = normal, dist
    width = np.diff(th)
    cidx = range(K) if closed else range(1, K)
    right_part, left_part = {}, {}
    for c in cidx:
        a = (c - 1) % K
        nA = n[a] - (T if c == 0 else 0.0)
        res = _corner(th[c], radius[c], nA, p[a], n[c], p[c],
                      0.5 * width[a], 0.5 * width[c], kappa)
        if res is None:
            return None
        kn, m, q = res
        split = np.searchsorted(kn, th[c])     # knots < t_c belong to piece a
        if c == 0:
            left_part[K] = (kn[:split] + T, m[:split] + T, q[:split])
        else:
            left_part[c] = (kn[:split], m[:split], q[:split])
        right_part[c] = (kn[split:], m[split:], q[split:])
    kn_all, m_all, q_all = [], [], []
    for k in range(K):
        start = right_part.get(k, (th[k:k + 1], n[k:k + 1], p[k:k + 1]))
        end = left_part.get(k + 1, (th[k + 1:k + 2], n[k:k + 1], p[k:k + 1]))
        kk = np.concatenate([start[0], end[0]])
        mm = np.concatenate([start[1], end[1]])
        qq = np.concatenate([start[2], end[2]])
        dup = np.flatnonzero(np.diff(kk) <= 1e-12 * width[k])
        kk, mm, qq = (np.delete(v, dup + 1) for v in (kk, mm, qq))
        kn_all.append(kk)
        m_all.append(mm)
        q_all.append(qq)
    knots = np.concatenate(kn_all)
    m = np.concatenate(m_all)
    q = np.concatenate(q_all)
    if closed:   # last knot: corner 0 one period later
        r0 = right_part[0]
        knots = np.append(knots, r0[0][0] + T)
        m = np.append(m, r0[1][0] + T)
        q = np.append(q, r0[2][0])
    keep = np.concatenate([[True], np.diff(knots) > 1e-12 * span])
    knots, m, q = knots[keep], m[keep], q[keep]
    if np.any(np.diff(knots) <= 0):
        return None
    return knots, m, 1.0 / q, np.zeros_like(q)


_STEP = math.pi / 4       # max turn of the rounding arc between knots
_LAM = 1.0                # ... and at most _LAM * (angle of the line to the ray)
_CUT = 0.8                # fraction of the (1 - kappa) allowance used by a fillet


def _corner(tc, rc, nA, pA, nB, pB, roomA, roomB, kappa):
    """Knots and local lines rounding the corner at angle tc (radius rc).

    A (left, normal nA, distance pA) and B (right) are the edges' lines in
    the corner's frame; roomA/roomB the angular room on each side. Convex
    corner: an arc tangent to A and B inside the corner, knots on the rays of
    N+1 arc points, local lines A, chords (P_{i-1}, P_{i+1}), B -- chords of a
    convex arc lie inside it, hence inside the polygon. Reflex corner: the
    lines scaled by c = (1+kappa)/2 (exact lines at +-room), an arc tangent
    to cA and cB turning right, local lines its tangents (below the arc).
    The arc size is halved until the certified bound holds on the corner's
    knot intervals. Returns arrays (knots, m, q), knots increasing, or None
    if no arc size is certified (the caller then uses the constants).
    """
    tau = nB - nA
    C = np.array([rc * math.cos(tc), rc * math.sin(tc)])
    tA = np.array([-math.sin(nA), math.cos(nA)])   # ccw edge directions
    tB = np.array([-math.sin(nB), math.cos(nB)])
    thl = np.array([tc - roomA, tc, tc + roomB])
    nrm = np.array([nA, nB])
    dst = np.array([pA, pB])
    if abs(tau) < 1e-9:     # straight "corner": the line itself
        return (np.array([tc]), np.array([nA]), np.array([pA]))
    # edge length available on each side: up to the ray at +-room
    lenA = _dist_to_ray(C, -tA, tc - roomA)
    lenB = _dist_to_ray(C, tB, tc + roomB)
    if tau > 0:
        c = 1.0
        cut = _CUT * (1.0 - kappa) * rc / (1.0 / math.cos(0.5 * tau) - 1.0)
    else:
        c = 0.5 * (1.0 + kappa)
        cut = _CUT * (1.0 - c) * rc / (1.0 / math.cos(0.5 * tau) - 1.0)
    L = min(0.5 * lenA, 0.5 * lenB, cut * math.tan(0.5 * abs(tau)))
    for _ in range(_MAX_HALVINGS):
        kn, m, q = _corner_lines(C, c, tA, tB, nA, pA, nB, pB, tau, L, tc, roomA, roomB)
        if kn is not None and np.all(np.diff(kn) > 0):
            # knots must stay in the room; certify on the two pieces
            ok = kn[0] >= tc - roomA and kn[-1] <= tc + roomB
            if ok:
                ratio = interval_ratios(kn, m, 1.0 / q, 0.0 * q, thl, nrm, dst, None)
                if np.all(ratio <= 1.0 + 1e-12) and np.all(ratio >= kappa):
                    return kn, m, q
        L *= 0.5
    return None


def _dist_to_ray(C, d, ang):
    """Distance s >= 0 along C + s d to the ray of angle ``ang`` (inf if none)."""
    e = np.array([math.cos(ang), math.sin(ang)])
    den = d[0] * e[1] - d[1] * e[0]
    if den == 0.0:
        return math.inf
    s = -(C[0] * e[1] - C[1] * e[0]) / den
    return s if s >= 0 else math.inf


def _arc_phis(O, R, sign, nA, tau):
    """Normal angles of the arc's knot points: steps <= _STEP and <= _LAM * eps,
    eps the angle between the tangent line and the ray. Near a nearly radial
    edge the steps shrink geometrically: blending two lines along rays is
    well conditioned only if they differ by less than their angle to the
    rays (otherwise the blend slides along the ray and folds back)."""
    f = nA + tau * np.linspace(0.0, 1.0, 65)
    P = O + sign * R * np.stack([np.cos(f), np.sin(f)], axis=-1)
    th = np.arctan2(P[:, 1], P[:, 0])
    eps = np.arcsin(np.clip(np.abs(np.cos(th - f)), 0.0, 1.0))
    step = np.clip(_LAM * eps, 1e-4, _STEP)
    dens = 1.0 / step
    s = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.abs(np.diff(f)))])
    N = int(np.clip(math.ceil(s[-1]), 2, 96))
    return np.interp(np.linspace(0.0, s[-1], N + 1), s, f)


def _corner_lines(C, c, tA, tB, nA, pA, nB, pB, tau, L, tc, roomA, roomB):
    R = L / math.tan(0.5 * abs(tau))
    TA = c * C - L * tA
    eA = np.array([math.cos(nA), math.sin(nA)])
    sign = 1.0 if tau > 0 else -1.0
    O = TA - sign * R * eA       # convex: circle inside; reflex: outside
    phi = _arc_phis(O, R, sign, nA, tau)
    if tau > 0:   # convex: arc points O + R e(phi), local lines = chords
        # the arc point on the corner ray is a knot too: A's and B's knot
        # intervals then end at the corner, so A (B) is never used beyond it
        e = np.array([math.cos(tc), math.sin(tc)])
        eo = e @ O
        disc = eo * eo - O @ O + R * R
        if not disc > 0:
            return None, None, None
        Pc = (eo + math.sqrt(disc)) * e
        phc = nA + np.mod(math.atan2(*(Pc - O)[::-1]) - nA, 2 * math.pi)
        if not nA < phc < nA + tau:
            return None, None, None
        i = int(np.searchsorted(phi, phc))
        near = [k for k in (i - 1, i) if 0 < k < len(phi) - 1
                and abs(phi[k] - phc) < 0.3 * (phi[i] - phi[i - 1])]
        phi = np.insert(np.delete(phi, near), i - (i - 1 in near), phc)
        eph = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        P = O + R * eph
        m_in, q_in = _line_through(P[:-2, 0], P[:-2, 1], P[2:, 0], P[2:, 1])
    else:         # reflex: arc points O - R e(phi), local lines = tangents
        eph = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        P = O - R * eph
        m_in, q_in = phi[1:-1], (P[1:-1] * eph[1:-1]).sum(axis=1)
    ang = tc + np.angle(np.exp(1j * (np.arctan2(P[:, 1], P[:, 0]) - tc)))
    m = np.concatenate([[nA], m_in, [nB]])
    q = np.concatenate([[c * pA], q_in, [c * pB]])
    if tau < 0:   # exact lines at the ends of the room
        ang = np.concatenate([[tc - roomA], ang, [tc + roomB]])
        m = np.concatenate([[nA], m, [nB]])
        q = np.concatenate([[pA], q, [pB]])
    if not np.all(q > 0):
        return None, None, None
    return ang, m, q


# ----------------------------------------------------------------- line blends
# Convex corner: the blend of two lines bulges outwards, so the lines are pulled in
# by c < 1 (allowance 1 - c); reflex corner: it bulges inwards (allowance
# c / kappa - 1). Per edge line one c, from the types of its two corners.
_BLEND_SAMPLES = 24       # sub-intervals per side in blend_check
_BLEND_SHRINK = 0.85      # factor applied to a failing side's width


CONVEX_SCALE = 0.9        # c of a line next to a convex corner (adaptive: the floor)


def blend_scales(convex_start, convex_end, kappa):
    """Fixed rule (used when ADAPTIVE_SCALES is off): scale c of an edge line from
    the types of its end corners (True convex, False reflex, None straight/open):
    c = max(kappa, CONVEX_SCALE) at convex-only
    ends, 1 at reflex-only ends, halfway between for one of each."""
    cvx = np.asarray(convex_start, dtype=object), np.asarray(convex_end, dtype=object)
    has_c = (cvx[0] == True) | (cvx[1] == True)          # noqa: E712 (object arrays)
    has_r = (cvx[0] == False) | (cvx[1] == False)        # noqa: E712
    cc = max(kappa, CONVEX_SCALE)
    return np.where(has_c & has_r, 0.5 * (1.0 + cc), np.where(has_c, cc, 1.0)).astype(float)


ADAPTIVE_SCALES = True
_C_MAX = 0.97             # adaptive c of a convex-cornered line stays <= this


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
    points F(w)(alpha - w) <= F(w_hi)(alpha - w_lo) (F increasing): rigorous."""
    # keyed by the kernel's values (not its id: ids are reused after collection)
    w = np.linspace(0.0, 1.0, n)
    F = kernel.cdf_derivs(w, 0)[0]
    if mirrored:  # grid symmetric: 1 - w_k = w_(n-1-k)
        F = 1.0 - F[::-1]
    key = F.tobytes()
    G = _G_CACHE.get(key)
    if G is None:
        Fhi = np.append(F[1:], 1.0)
        G = np.max(np.where(w[None, :] <= w[:, None], Fhi[None, :] * (w[:, None] - w[None, :]),
                            0.0), axis=1)
        if len(_G_CACHE) > 16:
            _G_CACHE.clear()
        _G_CACHE[key] = G
    return G


def build_blend(theta, normal, dist, closed, span, kappa, kernel):
    """Edge lines (pulled in by c_k) blended directly across each corner.

    Consecutive collinear edges are merged; every remaining corner gets ONE GERBS
    transition between its two lines, as wide as the certified bound allows
    (initially half of each adjacent edge's angle, the whole edge at an open
    end), shrunk by :func:`fit_blend_widths`. Returns (knots, m, a, b, Rmin,
    Rmax) (R = u~ / u_exact over everything: rho~/rho in [1/Rmax, 1/Rmin]) or
    None if some corner cannot be certified.
    """
    K = len(dist)
    n, p = np.asarray(normal, float), np.asarray(dist, float)
    # corners between piece k-1 and k (closed: all k, piece -1 = K-1 one period back)
    ks = np.arange(K) if closed else np.arange(1, K)
    prev = (ks - 1) % K
    nprev = n[prev] - np.where(ks == 0, span, 0.0)
    tau = n[ks] - nprev
    straight = (np.abs(tau) <= 1e-10) & (np.abs(p[ks] - p[prev]) <= 1e-10 * p[ks])
    real = ks[~straight]
    if closed and real.size == 0:
        return None
    # super-pieces: runs of pieces between real corners, one line each
    if closed:
        starts = real
        ends = np.append(real[1:], real[0] + K)          # piece index of the next corner
    else:
        starts = np.concatenate([[0], real])
        ends = np.concatenate([real, [K]])
    th_ext = np.concatenate([theta[:-1], theta[:-1] + span, [theta[-1] + span]]) if closed \
        else theta
    t0 = th_ext[starts]
    t1 = th_ext[ends]
    sn = n[starts % K] + np.where(starts >= K, span, 0.0)
    sp = p[starts % K]
    P = len(starts)
    # corner j sits at the start of super-piece j (closed: all; open: j >= 1)
    cj = np.arange(P) if closed else np.arange(1, P)
    pj = (cj - 1) % P
    ctheta = t0[cj]
    nA = sn[pj] - np.where(cj == 0, span, 0.0) - ctheta if closed else sn[pj] - ctheta
    nB = sn[cj] - ctheta
    convex = (nB - nA) > 0
    cstart = np.full(P, None, dtype=object)
    cend = np.full(P, None, dtype=object)
    cstart[cj] = convex
    cend[pj] = convex
    width = t1 - t0
    # room: half an edge between two corners, the whole edge next to an open end
    roomA = np.where(cstart[pj] == None, 1.0, 0.5) * width[pj]    # noqa: E711
    roomB = np.where(cend[cj] == None, 1.0, 0.5) * width[cj]      # noqa: E711
    if not closed:
        roomA = np.where(pj == 0, width[pj], roomA)
        roomB = np.where(cj == P - 1, width[cj], roomB)
    if ADAPTIVE_SCALES:
        c = adaptive_scales(P, pj, cj, nA, sp[pj], nB, sp[cj], roomA, roomB, kappa, kernel)
    else:
        c = blend_scales(cstart, cend, kappa)
    wa, wb, ok, Rmin, Rmax = fit_blend_widths(nA, sp[pj], c[pj], nB, sp[cj], c[cj],
                                              roomA, roomB, kappa, kernel)
    if not ok.all():
        return None
    # pure stretch of super-piece k: [t0 + b(corner at its start), t1 - a(corner at its end)]
    bs = np.zeros(P)
    ae = np.zeros(P)
    bs[cj] = wb
    ae[pj] = wa
    lo, hi = t0 + bs, t1 - ae
    kn = np.stack([lo, hi], axis=1).ravel()
    mm = np.repeat(sn, 2)
    cc = np.repeat(c * sp, 2)
    if closed:
        kn = np.append(kn, lo[0] + span)
        mm = np.append(mm, sn[0] + span)
        cc = np.append(cc, c[0] * sp[0])
    # a pure stretch of zero length is one knot
    keep = np.concatenate([[True], np.diff(kn) > 1e-12 * max(span, 1e-300)])
    kn, mm, cc = kn[keep], mm[keep], cc[keep]
    if np.any(np.diff(kn) <= 0):
        return None
    pure = (1.0 / c).min(), (1.0 / c).max()
    return (kn, mm, 1.0 / cc, np.zeros_like(cc), float(min(Rmin.min(initial=np.inf), pure[0])),
            float(max(Rmax.max(initial=-np.inf), pure[1])))
