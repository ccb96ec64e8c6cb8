"""Fallback constructions of the smooth radial envelope (DESIGN section 4).

The default is :mod:`gerbs_core.gauge.blend` (the edge lines blended directly across
each corner); where it cannot be certified (never on the test and benchmark meshes,
possible on slivers) the envelope takes one of two older certified constructions of
rho~ = 1/u~, u~ = sum_j G_j u_j with local
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
