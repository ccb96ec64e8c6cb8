"""Spoke caps: shrink a star envelope's spikes along spokes that a neighbour covers.

At a sliver fan (Blender's Cone: the base vertices toward the apex; a UV sphere's
vertices next to its poles) the envelope rho~_v of a vertex v reaches far along the
spoke v -> w between two thin faces and little elsewhere: a spike, whose steep flanks
make the blend's derivatives large where the supports of v and w meet. Where w's own
support is round along that spoke it covers the spike's far part, so v's reach along
the spoke is capped there (docs/design.md, stage 4):

    u_new = (u~^p + U^p)^(1/p),   u~ = 1/rho~_v,   p = 4

so rho_new <= min(rho~_v, 1/U): supports only shrink and stay compactly inside the
star; the cover's thickness eps0 is measured on every surface as before, not certified.
U(theta) is a GERBS spline of constants on each corner sector [ta, tb] (knots ta,
tm = ta + h, tb, h = (tb - ta)/2):

    U = U_a (1 - F((theta - ta)/h)) on [ta, tm],   U = U_b F((theta - tm)/h) on [tm, tb]

F the cover's kernel (flat at 0 and 1: U is C-infinity across spokes and at tm), U_a /
U_b the caps of the sector's start / end spoke, one value per directed edge, so the two
sectors beside a spoke see the same number. For the spoke v -> w of length L:

    R = max((L - BETA rho~_w(toward v)) / GAMMA, MU min_theta rho~_v),
    U_vw = 1/R  if R < rho~_v(spoke), v -> w is a spike and w -> v is not, else 0;

a spike: rho~_v(spoke) > SIGMA rho~_v(middle of the sector) in both sectors beside it.
Boundary spokes (no twin; crease rays of a cut mesh) are never capped: rho~ on a crease
ray must not depend on the side. Where no spoke is capped the cover is unchanged, bit
for bit.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ..splines.evaluate import falling_jet, rising_jet

__all__ = ["SpokeCaps", "spoke_caps", "disabled"]

# BETA, GAMMA: the spoke beyond GAMMA R from v is left to w's support where g_w <= BETA
# (psi_w well above 0 there, so the cover stays thick); MU: the cap stays >= twice v's
# shortest reach (the capped support stays round, its bump's slope bounded); SIGMA: a
# spike reaches SIGMA times further than mid-sector (Cone 8.6, UV sphere 4.1 next to the
# poles; icospheres, tori, the Cube, airplane, bone at most 1.6). Spikes both ways (the
# Cylinder's sides, 6.8) are not capped: neither support covers the other's. The
# prototype's values (issue 11's Cone investigation), measured with bench_shape.
BETA, GAMMA, MU, SIGMA = 0.65, 0.8, 2.0, 3.0
P = 4                    # soft minimum: U <= u~ / 2 changes u by < 1.6% ((1 + 2^-4)^(1/4))
MIN_SAMPLES = 65         # per sector, for min_theta rho~_v (only at vertices with a candidate cap)

_ENABLED = [True]


@contextmanager
def disabled():
    """Build covers without caps inside the block (the bench / test control)."""
    _ENABLED.append(False)
    try:
        yield
    finally:
        _ENABLED.pop()


@dataclass(frozen=True)
class SpokeCaps:
    """Per corner (C,): caps ``Ua`` / ``Ub`` (1 / length, 0: none) of its sector's start /
    end spoke, the sector ``ta``, ``tb`` (unfolded angles); ``kernel`` the transition F;
    ``capped`` (C,) bool: corners whose sector carries a cap."""

    Ua: np.ndarray
    Ub: np.ndarray
    ta: np.ndarray
    tb: np.ndarray
    kernel: object
    capped: np.ndarray

    def profile(self, corners, theta, nu: int):
        """[U, U', U''][:nu + 1] at unfolded angles theta (corners broadcast against it)."""
        c = np.broadcast_to(corners, theta.shape)
        ta, tb = self.ta[c], self.tb[c]
        h = 0.5 * (tb - ta)
        first = theta <= ta + h
        w = np.clip(np.where(first, theta - ta, theta - ta - h) / h, 0.0, 1.0)
        rise = rising_jet(self.kernel, w, h, nu)
        return list(np.where(first, self.Ua[c] * falling_jet(rise), self.Ub[c] * rise))

    def apply(self, u, corners, theta, nu: int):
        """u_new = (u~^p + U^p)^(1/p) and its theta-derivatives from the jet u of u~
        (chain rule, exact given the jets); u itself where U = 0. corners and theta as
        for :meth:`~gerbs_core.mesh.cover.StarCover.reciprocal_radius`."""
        if nu > 2:
            raise ValueError(f"spoke caps: derivatives up to order 2, not {nu}")
        theta, corners = np.asarray(theta, dtype=np.float64), np.asarray(corners)
        if corners.ndim and corners.shape == theta.shape[:-1]:
            corners = corners[..., None]        # one corner per row of samples
        corners = np.broadcast_to(corners, theta.shape)
        if not self.capped[corners].any():
            return u
        U = self.profile(corners, theta, nu)
        A = u[0] ** P + U[0] ** P
        f = u[0] * (1.0 + (U[0] / u[0]) ** P) ** (1.0 / P)     # >= u~ in floating point too
        out = [f]
        if nu >= 1:
            A1 = P * (u[0] ** (P - 1) * u[1] + U[0] ** (P - 1) * U[1])
            out.append(f * A1 / (P * A))
        if nu >= 2:
            A2 = P * ((P - 1) * (u[0] ** (P - 2) * u[1] ** 2 + U[0] ** (P - 2) * U[1] ** 2)
                      + u[0] ** (P - 1) * u[2] + U[0] ** (P - 1) * U[2])
            out.append(f * (A2 / (P * A) + (1.0 / P) * (1.0 / P - 1.0) * (A1 / A) ** 2))
        on = U[0] > 0.0
        return [np.where(on, a, b) for a, b in zip(out, u)]


def _spoke_ids(topo):
    """Directed-edge ids of each corner's start / end spoke and of their reverses (C,):
    half-edge c (vertex(c) -> vertex(next c)) is id c; the reverse of half-edge h is its
    twin, or C + h on the boundary."""
    C = topo.n_corners
    twin, prv = np.asarray(topo.halfedge_twin), np.asarray(topo.corner_prev)
    rev = np.where(twin >= 0, twin, C + np.arange(C))
    return np.arange(C), rev[prv], rev


def spoke_caps(topo, charts, corners2d, u_of, kernel) -> SpokeCaps | None:
    """The caps of a cover whose reciprocal envelope is ``u_of(corners, theta)`` (values
    only; corners2d the face layouts, kernel the cover's), or None where no spoke
    qualifies (or caps are disabled). Vectorized over all corners; min_theta rho~ is
    sampled only at vertices with a candidate cap."""
    if not _ENABLED[-1]:
        return None
    C = topo.n_corners
    cs = np.arange(C)
    nxt, prv = np.asarray(topo.corner_next), np.asarray(topo.corner_prev)
    ta = np.asarray(charts.theta0, dtype=np.float64)
    tb = ta + charts.alpha
    rho_a, rho_m, rho_b = (1.0 / u_of(cs[:, None], np.stack([ta, 0.5 * (ta + tb), tb], 1))).T
    ida, idb, rev_a = _spoke_ids(topo)
    spike = np.full(2 * C, np.inf)       # per directed edge: min over its sectors
    np.minimum.at(spike, ida, rho_a / rho_m)
    np.minimum.at(spike, idb, rho_b / rho_m)
    twin = np.asarray(topo.halfedge_twin)
    # spoke a of corner c is half-edge c, its reverse w -> v spoke b of corner next(c)
    cand = (spike[ida] > SIGMA) & (spike[rev_a] <= SIGMA) & (twin >= 0)
    if not cand.any():
        return None
    L = np.linalg.norm(corners2d[nxt] - corners2d, axis=1)
    rho_w = 1.0 / u_of(nxt, tb[nxt])                   # w's reach toward v
    vert = np.asarray(topo.face_vertices)
    need = np.isin(vert, vert[cand])
    s = np.linspace(0.0, 1.0, MIN_SAMPLES)
    cn = cs[need]
    rmin_c = 1.0 / u_of(cn[:, None], ta[cn, None] + s[None] * charts.alpha[cn, None]).max(axis=1)
    rmin_v = np.full(topo.n_vertices, np.inf)
    np.minimum.at(rmin_v, vert[cn], rmin_c)
    R = np.maximum((L - BETA * rho_w) / GAMMA, MU * rmin_v[vert])
    cap = np.zeros(2 * C)
    cap[:C] = np.where(cand & (R < rho_a), 1.0 / np.where(cand, R, 1.0), 0.0)
    if not cap.any():
        return None
    Ua, Ub = cap[ida], cap[idb]
    arrays = (Ua, Ub, ta.copy(), tb, (Ua > 0) | (Ub > 0))
    for a in arrays:
        a.flags.writeable = False
    return SpokeCaps(*arrays[:4], kernel, arrays[4])
