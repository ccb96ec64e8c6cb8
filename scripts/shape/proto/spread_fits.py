"""Prototype: extra candidate fits at vertices whose cage star spreads (largest angle between
a star face's normal and the vertex's mean normal) above ``spread`` degrees -- fits that
also see the star's cage faces: sample points of every star face (a lattice of
resolution ``res``) with targets on the face's cage (its barycentric / bilinear point),
weighted ``kappa`` against the ring data (each group's weights summing to 1; ring-1 data
times ``boost``). Each kind (degree, data rings, kappa, boost) is one extra candidate,
offered only at the spread stars (an infinite choice penalty elsewhere), so meshes
without spread stars are bit-identical. Linear in X: c = matrix @ X with the pin.
The variant ``gated`` (kinds ((4, 2, 1.0, 1.0),), gate 0.5) became the default
(gerbs_core.mesh.spread_fits); every variant's numbers are in docs/design.md ("Folds").
The production candidate is switched off inside (rule spread 180) while it runs."""
import dataclasses
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
from gerbs_core.mesh.fits import MAX_CONDITION, CandidateFits, pinned_normal_inverse  # noqa: E402
from gerbs_core.mesh.lattice import Lattice  # noqa: E402
from gerbs_core.mesh.monomials import monomial_exponents, monomials, n_monomials  # noqa: E402
from gerbs_core.mesh.spread_fits import star_spread  # noqa: E402

OPTS = {"spread": 60.0, "res": 4, "kinds": ((2, 1, 1.0, 1.0),), "cage_w": "face",
        "ctx": None, "n_extra": 0, "mask": None, "only": False}


def _cage_samples(topo, charts, corners2d, v, lat, x, cw):
    """Chart points (n, 2), target weights (n, V) sparse rows, per-face weights (n,) of the
    cage samples of v's star faces (the sample at v itself left out)."""
    ys, rows, wts = [], [], []
    lo = lat.local_offsets
    for c in np.flatnonzero(topo.face_vertices == v):
        f = topo.corner_face[c]
        idx = np.arange(lo[f], lo[f + 1])
        y = charts.to_chart(np.full(len(idx), c), x[idx])[0]
        n = topo.face_sizes[f]
        corners = topo.face_vertices[topo.face_offsets[f] + np.arange(n)]
        keep = np.hypot(y[:, 0], y[:, 1]) > 1e-9 * max(np.abs(y).max(), 1e-300)
        T = np.zeros((keep.sum(), topo.n_vertices))
        np.add.at(T, (np.repeat(np.arange(keep.sum()), n), np.tile(corners, keep.sum())),
                  cw[idx][keep, :n].ravel())
        ys.append(y[keep])
        rows.append(T)
        wts.append(np.full(keep.sum(), 1.0 / len(idx)))
    return np.concatenate(ys), np.concatenate(rows), np.concatenate(wts)


def spread_candidates(topo, charts, corners2d, rings, X, kinds):
    """(extra CandidateFits list, spiky mask (V,)): the kinds' fits at the spread stars
    (rows of other vertices empty)."""
    V = topo.n_vertices
    spiky = star_spread(topo, X) > OPTS["spread"]
    lat = Lattice(topo, OPTS["res"])
    x = lat.map_to_polygon(corners2d, local=True)
    cw = lat.corner_weights(local=True)
    out = []
    for degree, layers, kappa, boost in kinds:
        M = n_monomials(degree)
        deg = monomial_exponents(degree).sum(1)
        rr, cc, mv, rv = [], [], [], []
        normal = np.zeros((V, M, M))
        for v in np.flatnonzero(spiky):
            h = rings.h[v]
            s0, s1 = rings.offsets[v], rings.offsets[v + 1]
            use = rings.ring[s0:s1] <= layers
            if layers < 2:   # the base fits' rule: too few or ill-conditioned ring-1 data
                y1 = rings.y[s0:s1][use] / h
                B1 = monomials(y1, degree)[0]
                N1 = (B1 / (y1 ** 2).sum(1)[:, None]).T @ B1
                lam = np.linalg.eigvalsh(N1)
                if use.sum() < M + 2 or lam[-1] > MAX_CONDITION * max(lam[0], 1e-300):
                    use = rings.ring[s0:s1] <= 2
            if use.sum() < M + 2:   # ... and rings 1-2 too few: ring 3 (boundary corners)
                use = rings.ring[s0:s1] <= 3
            yd = rings.y[s0:s1][use] / h
            d2 = (yd ** 2).sum(1)
            wd = np.where(rings.ring[s0:s1][use] == 1, boost, 1.0) / d2
            Td = np.zeros((use.sum(), V))
            Td[np.arange(use.sum()), rings.ids[s0:s1][use]] = 1.0
            parts = [(yd, Td, wd / wd.sum())]
            if kappa:
                yc, Tc, wc = _cage_samples(topo, charts, corners2d, v, lat, x, cw)
                yc = yc / h
                if OPTS["cage_w"] == "inv2":
                    wc = wc / np.maximum((yc ** 2).sum(1), 1e-12)
                parts.append((yc, Tc, kappa * wc / wc.sum()))
            y = np.concatenate([p[0] for p in parts])
            T = np.concatenate([p[1] for p in parts])
            w = np.concatenate([p[2] for p in parts])
            w = w / w.sum()
            cols = np.flatnonzero(np.abs(T).sum(0) > 0)
            T = T[:, cols]
            B = monomials(y, degree)[0]
            bw = (B * w[:, None]).T                     # (M, n)
            N = bw @ B
            P = pinned_normal_inverse(N[None], degree)[0]
            A = (P @ bw) / h ** deg[:, None]
            for val, tgt in ((A, mv), (bw, rv)):
                blk = val @ T
                tgt.append(np.concatenate([blk.ravel(), -val.sum(1)]))
            rr.append(np.concatenate([np.repeat(v * M + np.arange(M), len(cols)),
                                      v * M + np.arange(M)]))
            cc.append(np.concatenate([np.tile(cols, M), np.full(M, v)]))
            normal[v] = N
        cat = (lambda a: np.concatenate(a) if a else np.zeros(0))
        rr, cc = cat(rr).astype(np.int64), cat(cc).astype(np.int64)
        mat = sp.csr_matrix((cat(mv), (rr, cc)), shape=(V * M, V))
        rhs = sp.csr_matrix((cat(rv), (rr, cc)), shape=(V * M, V))
        out.append(CandidateFits(degree, mat, normal, rhs))
    return out, spiky


def candidates(rings, rules, _old=ag.candidate_fits_all):
    base = _old(rings, rules)
    topo, charts, corners2d, X = OPTS["ctx"]
    extra, spiky = spread_candidates(topo, charts, corners2d, rings, X, OPTS["kinds"])
    OPTS["n_extra"], OPTS["mask"] = len(extra), spiky
    if OPTS["only"]:     # the extra kinds replace the base candidates at spread stars
        OPTS["n_base"] = len(base)
    else:
        OPTS["n_base"] = 0
    return base + extra


def penalty(cands, X, smp, fn, h, rule, coefs=None, _old=ag._fold_penalty):
    out = _old(cands, X, smp, fn, h, rule, coefs)
    k = OPTS["n_extra"]
    if k:
        off = ~OPTS["mask"][smp.vertex]
        if OPTS.get("gate"):   # an extra only where it folds less than every base candidate
            V = len(OPTS["mask"])
            E = np.stack([np.bincount(smp.vertex, out[:, i], minlength=V)
                          for i in range(out.shape[1])], 1)
            best = E[:, :-k].min(1)
            worse = E[:, -k:] >= OPTS["gate"] * best[:, None]
            out[:, -k:][worse[smp.vertex]] = np.inf
        out[off, -k:] = np.inf
        if OPTS["n_base"]:
            out[~off, :-k] = np.inf
    return out


def fair_fits(topo, charts, corners2d, cover, rings, X, rule, sharp=None, constraints=None,
              _old=ag.fair_fits):
    OPTS["ctx"] = (topo, charts, corners2d, X)
    # the production candidate (mesh.spread_fits) off: this module's kinds replace it
    rule = dataclasses.replace(rule, spread=180.0)
    return _old(topo, charts, corners2d, cover, rings, X, rule, sharp, constraints)


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "fair_fits", fair_fits),
                                 (ag, "candidate_fits_all", candidates),
                                 (ag, "_fold_penalty", penalty)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with this module's change."""
    return run_variant(patched, V, F, r, exact=exact, **opts)


def cage4(V, F, r, exact=True):
    """Variant: the degree-4 rings 1-2 fit with the star's cage samples at weight 0.3."""
    return variant(V, F, r, exact=exact, kinds=((4, 2, 0.3, 1.0),))


def cage2(V, F, r, exact=True):
    """Variant: the degree-2 ring-1 fit with the star's cage samples at weight 1."""
    return variant(V, F, r, exact=exact, kinds=((2, 1, 1.0, 1.0),))


def gated(V, F, r, exact=True):
    """Variant: the degree-4 rings 1-2 fit with the cage samples at weight 1, offered only
    where its fold penalty is below half the base candidates' least."""
    return variant(V, F, r, exact=exact, kinds=((4, 2, 1.0, 1.0),), gate=0.5)
