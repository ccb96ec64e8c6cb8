"""Prototype: vertex charts that do not stretch obtuse corners as much (issue 11, the cow).

The default chart scales every angle of v's unfolded star by s_v = 2 pi / T_v. Here the
chart angle is a C-infinity increasing map phi_v(theta) of the unfolded angle with
phi_v(T_v) = 2 pi that sends each corner's sector [Theta_k, Theta_k + a_k] onto a target
width b_k (the targets sum to 2 pi): an ERBS blend of lines through the spokes' targets,

    phi = (1 - F(t)) L_k(theta) + F(t) L_{k+1}(theta),  t = (theta - Theta_k) / a_k,
    L_k(theta) = Phi_k + m_k (theta - Theta_k),  m_k = min(b_{k-1}/a_{k-1}, b_k/a_k),

F the cover's kernel (flat at 0 and 1, so phi is C-infinity across the spokes and linear
there with slope m_k; m_k <= both neighbours' ratios makes L_{k+1} - L_k >= 0 inside the
sector, so phi' > 0). Only interior vertices with a corner wider than ``angle`` degrees in
the default chart (s_v a_k > angle) get it; every other vertex keeps s_v theta bit for bit.

Targets (``rule``): "cap": a wide corner gets max(a_k, min(s_v a_k, angle)) and the other
corners share the rest in proportion to a_k (``obtuse``: only corners whose layout angle
exceeds it count as wide); "power": b_k proportional to a_k^p.

Charts enter the core through ``VertexCharts.to_chart`` (evaluation, stencil, fits'
samples) and the data rings (``rings._chart_points``, ``rings._ring1``); those are patched.
``from_chart`` (chart_eval, tests only) is not."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.charts as chm  # noqa: E402
import gerbs_core.mesh.rings as rg  # noqa: E402
from gerbs_core.kernels.erbs import ERBS  # noqa: E402

OPTS = {"angle": 135.0, "rule": "cap", "p": 0.5, "obtuse": 0.0}
KERNEL = ERBS()


def targets(a, s, star, wide_v):
    """(C_star,) target widths b of the star-ordered corners (a their layout angles, s the
    vertices' default scales per corner, star the vertex of each, wide_v (V,) which
    vertices get the rule)."""
    A = np.deg2rad(OPTS["angle"])
    V = len(wide_v)
    b = s * a
    if OPTS["rule"] == "power":
        w = a ** OPTS["p"]
        tot = np.bincount(star, w, minlength=V)
        bp = 2 * np.pi * w / tot[star]
    else:
        big = (s * a > A) & (a > np.deg2rad(OPTS["obtuse"]))
        bb = np.where(big, np.maximum(a, np.minimum(s * a, A)), 0.0)
        rest = 2 * np.pi - np.bincount(star, bb, minlength=V)
        small_sum = np.bincount(star, np.where(big, 0.0, a), minlength=V)
        bp = np.where(big, bb, a * rest[star] / np.maximum(small_sum[star], 1e-300))
    return np.where(wide_v[star], bp, b)


def attach(topo, ch):
    """Per-corner tables (Phi0, b, m0, m1, on) of phi, set on the charts as ``_phi``."""
    so = np.asarray(topo.star_offsets, dtype=np.int64)
    sc = np.asarray(topo.star_corners, dtype=np.int64)
    V = len(so) - 1
    star = np.repeat(np.arange(V), np.diff(so))
    a = ch.alpha[sc]
    s = ch.scale[star]
    wide = np.zeros(V, bool)
    np.logical_or.at(wide, star, (s * a > np.deg2rad(OPTS["angle"]))
                     & (a > np.deg2rad(OPTS["obtuse"])))
    wide &= ~np.asarray(ch.boundary, bool)
    b = targets(a, s, star, wide)
    start = np.concatenate([[0.0], np.cumsum(b)])[so[:-1]]
    phi0 = np.cumsum(b) - b - start[star]
    ratio = b / a
    pos = np.arange(len(sc)) - so[star]
    n = np.diff(so)[star]
    prev = so[star] + (pos - 1) % n
    nxt = so[star] + (pos + 1) % n
    m0 = np.minimum(ratio[prev], ratio)
    m1 = np.minimum(ratio, ratio[nxt])
    C = len(ch.alpha)
    tab = {k: np.zeros(C) for k in ("phi0", "b", "m0", "m1")}
    for k, val in (("phi0", phi0), ("b", b), ("m0", m0), ("m1", m1)):
        tab[k][sc] = val
    on = np.zeros(C, bool)
    on[sc] = wide[star]
    tab["on"] = on
    tab["key"] = ch.theta0[sc] + 1000.0 * star  # sorted: the sector lookup of any angle
    tab["sc"], tab["so"] = sc, so
    object.__setattr__(ch, "_phi", tab)
    return int(wide.sum())


def phi_sector(tab, ch, c, th):
    """phi, phi', phi'' at unfolded angles th of corner c's sector (elementwise)."""
    a = ch.alpha[c]
    u = th - ch.theta0[c]
    t = np.clip(u / a, 0.0, 1.0)
    F = KERNEL.cdf_derivs(t, 2)
    inside = (u > 0) & (u < a)
    F1, F2 = np.where(inside, F[1], 0.0), np.where(inside, F[2], 0.0)
    L0 = tab["phi0"][c] + tab["m0"][c] * u
    L1 = tab["phi0"][c] + tab["b"][c] + tab["m1"][c] * (u - a)
    d = L1 - L0
    p = L0 + F[0] * d
    p1 = tab["m0"][c] + F[0] * (tab["m1"][c] - tab["m0"][c]) + F1 / a * d
    p2 = 2 * F1 / a * (tab["m1"][c] - tab["m0"][c]) + F2 / (a * a) * d
    return p, p1, p2


def phi_any(ch, v, th):
    """phi_v(th) for any unfolded angle (extended by phi(th + T) = phi(th) + 2 pi)."""
    tab = ch._phi
    T = ch.span[v]
    n = np.floor(th / T)
    thw = th - n * T
    so, sc = tab["so"], tab["sc"]
    j = np.searchsorted(tab["key"], thw + 1000.0 * v, side="right") - 1
    j = np.clip(j, so[v], so[v + 1] - 1)
    c = sc[j]
    p = phi_sector(tab, ch, c, thw)[0] + 2 * np.pi * n
    return np.where(tab["on"][c], p, ch.scale[v] * th)


def to_chart(self, corner, x, nu=0, clamp=True, pol=None, _old=chm.VertexCharts.to_chart):
    tab = getattr(self, "_phi", None)
    corner = np.asarray(corner)
    if tab is None or not tab["on"][corner].any():
        return _old(self, corner, x, nu, clamp, pol)
    if pol is None or len(pol) < nu + 1:
        pol = self.polar(corner, x, nu, clamp)
    r, th = pol[0]
    s = self.scale[self.corner_vertex[corner]]
    corner = np.broadcast_to(corner, th.shape)
    q, q1, q2 = phi_sector(tab, self, corner, th)
    on = tab["on"][corner]
    phi = np.where(on, q, s * th)
    p1 = np.where(on, q1, s)
    p2 = np.where(on, q2, 0.0)
    cp, sp = np.cos(phi), np.sin(phi)
    out = [np.stack([r * cp, r * sp], axis=-1)]
    if nu < 1:
        return out
    dr, dpsi = pol[1]
    sdp = p1[..., None] * dpsi
    dy1 = cp[..., None] * dr - (r * sp)[..., None] * sdp
    dy2 = sp[..., None] * dr + (r * cp)[..., None] * sdp
    out.append(np.stack([dy1, dy2], axis=-2))
    if nu < 2:
        return out
    Hr, Hp = pol[2]
    ss, s2 = p1[..., None, None], p2[..., None, None]
    sym = dr[..., :, None] * dpsi[..., None, :] + dpsi[..., :, None] * dr[..., None, :]
    pp = dpsi[..., :, None] * dpsi[..., None, :]
    C, S, R = cp[..., None, None], sp[..., None, None], r[..., None, None]
    h1 = C * Hr - S * ss * sym - R * C * ss * ss * pp - R * S * ss * Hp - R * S * s2 * pp
    h2 = S * Hr + C * ss * sym - R * S * ss * ss * pp + R * C * ss * Hp + R * C * s2 * pp
    out.append(np.stack([h1, h2], axis=-3))
    return out


def chart_points(charts, corner, z, tref, _old=rg._chart_points):
    tab = getattr(charts, "_phi", None)
    if tab is None:
        return _old(charts, corner, z, tref)
    th = tref + np.angle(z * np.exp(-1j * tref))
    r = np.abs(z)
    phi = phi_any(charts, charts.corner_vertex[corner], th)
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=-1)


def ring1(topo, charts, corners2d, _old=rg._ring1):
    """rings._ring1 with the chart angle phi (the other corners of a corner's face lie in
    its sector)."""
    if getattr(charts, "_phi", None) is None:
        return _old(topo, charts, corners2d)
    sizes, off, cf = topo.face_sizes, topo.face_offsets, topo.corner_face
    vs, qs, ys = [], [], []
    for n in np.unique(sizes).tolist():
        cs = np.flatnonzero(sizes[cf] == n)
        k = cs - off[cf[cs]]
        idx = off[cf[cs]][:, None] + (k[:, None] + 1 + np.arange(n - 1)) % n
        cc = np.broadcast_to(cs[:, None], idx.shape)
        r, th = charts.unfolded(cc, corners2d[idx])
        s = charts.scale[charts.corner_vertex[cs]][:, None]
        q = phi_sector(charts._phi, charts, cc, th)[0]
        phi = np.where(charts._phi["on"][cc], q, s * th)
        ys.append(np.stack([r * np.cos(phi), r * np.sin(phi)], -1).reshape(-1, 2))
        vs.append(np.repeat(charts.corner_vertex[cs], n - 1))
        qs.append(topo.face_vertices[idx].ravel())
    return np.concatenate(vs), np.concatenate(qs), np.concatenate(ys)


STATS = {}


def vertex_charts(topo, corners2d, angles, rule="keep", scale=None, _old=chm.vertex_charts):
    ch = _old(topo, corners2d, angles, rule, scale)
    STATS["wide"] = attach(topo, ch)
    return ch


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "vertex_charts", vertex_charts),
                                 (chm.VertexCharts, "to_chart", to_chart),
                                 (rg, "_chart_points", chart_points), (rg, "_ring1", ring1)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with these charts."""
    return run_variant(patched, V, F, r, exact=exact, **opts)


def cap135(V, F, r, exact=True):
    return variant(V, F, r, exact, angle=135.0, rule="cap")


def cap120(V, F, r, exact=True):
    return variant(V, F, r, exact, angle=120.0, rule="cap")


def cap150(V, F, r, exact=True):
    return variant(V, F, r, exact, angle=150.0, rule="cap")


def pow50(V, F, r, exact=True):
    return variant(V, F, r, exact, angle=135.0, rule="power", p=0.5)


def cap135_obtuse(V, F, r, exact=True):
    return variant(V, F, r, exact, angle=135.0, rule="cap", obtuse=120.0)


def cap150_obtuse(V, F, r, exact=True):
    return variant(V, F, r, exact, angle=150.0, rule="cap", obtuse=120.0)
