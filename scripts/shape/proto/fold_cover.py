"""Prototype: a fold-aware cover (issue 11, the cow's folds).

Most of the cow's pairs above 90 degrees are folds of the surface (scripts/shape/folds.py
``--exact``): a local function l_v that turns against a star face (normal of l_v o zeta_v
more than ``turn`` degrees from the rest face's) where Psi_v is large. Here the surface is
built twice: the first build finds, for every corner c (vertex v, face f), the points of
f's lattice (resolution ``res``) where Psi_v > ``psi`` and l_v o zeta_v turns; the cover of
the second build caps v's reach in c's sector at ``factor`` times the smallest unfolded
radius of those points, through the spoke caps' soft minimum (gerbs_core.mesh.spoke_caps:
u = (u~^4 + U^4)^(1/4)) with U a GERBS spline of constants whose knot in the middle of the
sector carries 1 / R (and, with ``spokes``, the spokes beside it the larger of their
sectors' caps): C-infinity across spokes, supports only shrink. The fits are chosen again
on the capped cover. Where no corner turns the second build is the first.

Measured (docs/design.md, "Folds"): every corner where l_v turns against its face does so
at v itself (l_v's tangent plane; the cow's 45 such corners), so the cap falls on the
first lattice ring and the cover has holes (``require_cover`` fails on the cow): not kept.
Points at v are left out (r > 0) since no cap inside the star changes S = l_v there."""
import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core  # noqa: E402
from gerbs_core import BlendingSurface  # noqa: E402
import gerbs_core.mesh.spoke_caps as sk  # noqa: E402
from gerbs_core.mesh.monomials import monomials  # noqa: E402
from gerbs_core.splines.evaluate import falling_jet, rising_jet  # noqa: E402

OPTS = {"turn": 90.0, "psi": 0.05, "factor": 0.8, "res": 8, "spokes": False, "passes": 1}
CAPS = {"Um": None}
STATS = {}


@dataclasses.dataclass(frozen=True)
class FoldCaps(sk.SpokeCaps):
    """SpokeCaps with a knot value ``Um`` (C,) in the middle of every sector."""
    Um: np.ndarray = None

    def profile(self, corners, theta, nu: int):
        """The spoke caps' profile plus Um's knot: Um F on the first half, Um (1 - F) on
        the second (the same local coordinate as the parent's)."""
        base = super().profile(corners, theta, nu)
        c = np.broadcast_to(corners, theta.shape)
        ta, h = self.ta[c], 0.5 * (self.tb[c] - self.ta[c])
        first = theta <= ta + h
        rise = rising_jet(self.kernel, np.clip((theta - ta - np.where(first, 0.0, h)) / h,
                                               0.0, 1.0), h, nu)
        mid = np.where(first, rise, falling_jet(rise)) * self.Um[c]
        return [b + m for b, m in zip(base, mid)]


def caps_with_folds(topo, charts, corners2d, u_of, kernel, _old=sk.spoke_caps):
    base = _old(topo, charts, corners2d, u_of, kernel)
    Um = CAPS["Um"]
    if Um is None or not (Um > 0).any():
        return base
    C = topo.n_corners
    ta = np.asarray(charts.theta0, dtype=np.float64)
    tb = ta + charts.alpha
    Ua = np.zeros(C) if base is None else np.array(base.Ua)
    Ub = np.zeros(C) if base is None else np.array(base.Ub)
    if OPTS["spokes"]:
        ida, idb, _ = sk._spoke_ids(topo)
        spoke = np.zeros(2 * C)   # per spoke (directed edge from v): the larger sector cap
        np.maximum.at(spoke, ida, Um)
        np.maximum.at(spoke, idb, Um)
        Ua, Ub = np.maximum(Ua, spoke[ida]), np.maximum(Ub, spoke[idb])
    capped = (Ua > 0) | (Ub > 0) | (Um > 0)
    return FoldCaps(Ua, Ub, ta, tb, kernel, capped, Um)


def turning_caps(s):
    """(C,) 1 / R per corner (0: none) of the built surface s (module docstring)."""
    topo, ch, lay = s.model.topology, s.charts, s.layouts.corners
    lat = s.lattice(OPTS["res"])
    x = lat.map_to_polygon(lay, local=True)
    f = np.asarray(lat.local_face)
    X = s.vertices
    off = np.asarray(topo.face_offsets)
    # rest normals of the faces (Newell)
    fv = np.asarray(topo.face_vertices)
    nxt = np.asarray(topo.corner_next)
    nf = np.zeros((topo.n_faces, 3))
    np.add.at(nf, topo.corner_face, np.cross(X[fv], X[fv[nxt]]))
    nf /= np.linalg.norm(nf, axis=1)[:, None]
    vs, Psi, _ = s.partition(f, x)
    Um = np.zeros(topo.n_corners)
    cos_t = np.cos(np.deg2rad(OPTS["turn"]))
    coef = s.coefficients.reshape(topo.n_vertices, -1, 3)
    for k in range(vs.shape[1]):
        live = (vs[:, k] >= 0) & (Psi[:, k] > OPTS["psi"])
        idx = np.flatnonzero(live)
        v = vs[idx, k]
        c = off[f[idx]] + k                       # partition slot k = corner k of the face
        assert (fv[c] == v).all()
        y, dy = ch.to_chart(c, x[idx], 1)
        dl = np.zeros((len(idx), 3, 2))
        for d in np.unique(s.degrees[v]).tolist():
            sel = np.flatnonzero(s.degrees[v] == d)
            mm = monomials(y[sel], d, 1)
            M = mm[0].shape[-1]
            dl[sel] = np.einsum("pmj,pmc->pcj", mm[1], coef[v[sel], :M])
        J = np.einsum("pcj,pjk->pck", dl, dy)
        n = np.cross(J[..., 0], J[..., 1])
        n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
        r = np.linalg.norm(x[idx] - ch.origin[c], axis=1)
        # r > 0: at v itself l_v o zeta_v is the vertex's tangent plane, which no cap changes
        bad = (np.einsum("pc,pc->p", n, nf[f[idx]]) < cos_t) & (r > 0)
        R = np.full(topo.n_corners, np.inf)
        np.minimum.at(R, c[bad], OPTS["factor"] * r[bad])
        hit = np.isfinite(R)
        Um[hit] = np.maximum(Um[hit], 1.0 / R[hit])
    return Um


def build(V, F, **kw):
    """The surface with the fold-aware cover (OPTS set by the caller)."""
    CAPS["Um"] = None
    s = BlendingSurface(V, F, **kw)
    Um_all = np.zeros(s.model.topology.n_corners)
    for _ in range(OPTS["passes"]):
        Um = turning_caps(s)
        if not (Um > Um_all).any():
            break
        Um_all = np.maximum(Um_all, Um)
        CAPS["Um"] = Um_all
        with patching({}, {}, [(sk, "spoke_caps", caps_with_folds)]):
            s = BlendingSurface(V, F, **kw)
        CAPS["Um"] = None
    STATS["capped"] = int((Um_all > 0).sum())
    return s


def patched(**opts):
    """BlendingSurface(V, F, ...) builds with the fold-aware cover inside the block."""
    return patching(OPTS, opts, [(gerbs_core, "BlendingSurface", build)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with the fold-aware cover."""
    return run_variant(patched, V, F, r, exact=exact, **opts)


def turn90(V, F, r, exact=True):
    return variant(V, F, r, exact)


def turn90_spokes(V, F, r, exact=True):
    return variant(V, F, r, exact, spokes=True)
