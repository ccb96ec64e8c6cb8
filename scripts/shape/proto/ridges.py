"""Prototype: ridge (soft-crease) candidate fits at vertices with a sharp star edge (issue 11,
Suzanne's mouth corners).

At a vertex v with a star edge whose cage dihedral exceeds ``sharp`` degrees (below
``sharp_max``), one more candidate l_v(y) = X_v + sum_m c_m y^m (degree ``poly``) + sum_j
d_j r_j(y), one ridge function r_j per sharp star edge (up to ``kmax``; lines within
``merge`` degrees count once) of :mod:`ridge_basis` (``kind`` line / half, width
``delta`` x the edge's length, or x h with ``dscale`` "h"), fitted by pinned least
squares on rings 1-2 plus the star's cage samples at weight ``kappa``: linear in X,
constants give zero coefficients. Offered where its fold penalty is below ``gate`` x
the base candidates' least (as spread_fits.gate; ``margin``: its choice energy times
that), and with ``allow`` (V,) bool only there (:func:`targeted`: the corners of the
faces where the default surface folds).

The ridge slots follow the polynomial part's monomials in the padded degree-4 layout
(the candidate has "degree" 4), so the choice, the coupling and the output use the ridge
values wherever this module overrides the monomials of those vertices' rows: the
candidate values and the fold penalty of the choice, the coupling's rows (vertices that
chose it), the evaluation's corner terms and the stencil's monomial entries (the stencil
equals the tessellation: tests/core/test_shape_prototypes.py). Not for creases.
Measured in docs/design.md ("Folds"): not kept.
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
import gerbs_core.mesh.assembly as asm  # noqa: E402
import gerbs_core.mesh.evaluate as ev  # noqa: E402
import gerbs_core.mesh.spread_fits as spf  # noqa: E402
from gerbs_core.mesh.monomials import monomials  # noqa: E402
from shape.proto.ridge_basis import MM, find_ridges, ridge_candidates  # noqa: E402

OPTS = {"sharp": 90.0, "sharp_max": 180.0, "quads": False, "spiky": False, "allow": None,
        "poly": 3, "kind": "half", "delta": 0.5, "dscale": "edge", "kmax": 5, "merge": 20.0,
        "kappa": 0.3, "metric": np.pi, "gate": 0.5, "margin": 1.0,
        # state of the current build
        "ctx": None, "ridges": None, "index": None, "active": None, "eval_u": None}


# ------------------------------------------------------------------ patches of the build
def candidates(rings, rules, _old=ag.candidate_fits_all):
    base = _old(rings, rules)
    topo, charts, corners2d, X = OPTS["ctx"]
    spiky = spf.star_spread(topo, X) > spf.SPREAD if OPTS["spiky"] else None
    rd = find_ridges(topo, rings, X, OPTS, spiky)
    OPTS["ridges"], OPTS["rings_h"] = rd, rings.h
    if rd is None:
        OPTS["index"] = None
        return base
    OPTS["index"] = len(base)
    return base + [ridge_candidates(topo, charts, corners2d, rings, rd, OPTS["kappa"],
                                   OPTS["metric"])]


def _ridge_rows(vertex):
    rd = OPTS["ridges"]
    return np.flatnonzero(rd.at[vertex] >= 0)


def candidate_values(cands, X, vertex, Bu, coefs=None, _old=ag.candidate_values):
    out = _old(cands, X, vertex, Bu, coefs)
    i = OPTS["index"]
    if i is None:
        return out
    coefs = ag.candidate_coefs(cands, X) if coefs is None else coefs
    rows = _ridge_rows(vertex)
    smp = OPTS["smp"]
    B = OPTS["ridges"].basis(vertex[rows], smp.y[rows], OPTS["rings_h"])[0]
    C = coefs[i].reshape(-1, MM, 3)[vertex[rows]]
    out[rows, i] = X[vertex[rows]] + np.einsum("rm,rmc->rc", B, C)
    return out


def samples(*a, _old=ag._samples, **k):
    smp = _old(*a, **k)
    OPTS["smp"] = smp
    return smp


def penalty(cands, X, smp, fn, h, rule, coefs=None, _old=ag._fold_penalty):
    out = _old(cands, X, smp, fn, h, rule, coefs)
    i = OPTS["index"]
    if i is None:
        return out
    coefs = ag.candidate_coefs(cands, X) if coefs is None else coefs
    rows = _ridge_rows(smp.vertex)
    vr = smp.vertex[rows]
    dB = OPTS["ridges"].basis(vr, smp.y[rows], h, 1)[1]          # (r, MM, 2)
    C = coefs[i].reshape(-1, MM, 3)[vr]
    d = np.einsum("rmj,rmc->rcj", dB, C)
    nl = np.cross(d[..., 0], d[..., 1])
    nl /= np.maximum(np.linalg.norm(nl, axis=1, keepdims=True), 1e-300)
    pen = np.maximum(0.0, rule.fold_cos - np.einsum("ij,ij->i", nl, fn[smp.face[rows]])) ** 2
    out[:, i] = 0.0
    out[rows, i] = rule.fold * h[vr] ** 2 * smp.weight[rows] * smp.psi[rows] * pen
    # offered only at ridge vertices, and where it folds less than GATE x the base's least
    V = len(h)
    E = np.stack([np.bincount(smp.vertex, out[:, j], minlength=V) for j in range(i + 1)], 1)
    shut = (OPTS["ridges"].at < 0) | (E[:, i] >= OPTS["gate"] * E[:, :i].min(1))
    out[shut[smp.vertex], i] = np.inf
    OPTS["offered"] = np.flatnonzero(~shut)
    OPTS["E"] = E
    return out


def choose(cands, X, smp, rule, V, penalty, coefs=None, _old=ag._choose):
    choice = _old(cands, X, smp, rule, V, penalty, coefs)
    i = OPTS["index"]
    if i is not None:
        OPTS["active"] = np.flatnonzero(choice == i)
        act = np.zeros(V, bool)
        act[OPTS["active"]] = True
        rd = OPTS["ridges"]
        rd.at = np.where(act, rd.at, -1)     # from here on: the chosen ones only
        if not act.any():
            OPTS["index"] = None
    return choice


def first_minimum(E, tie=ag.TIE, _old=ag.first_minimum):
    """The choice, with the ridge candidate's energy times OPTS["margin"] (> 1: it must win
    by that factor)."""
    i = OPTS["index"]
    if i is not None and OPTS["margin"] != 1.0 and E.shape[1] > i:
        E = E.copy()
        E[:, i] *= OPTS["margin"]
    return _old(E, tie)


def coupled(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints=None, mu=None,
            _old=ag.coupled_fits):
    if OPTS["index"] is not None:
        rows = _ridge_rows(smp.vertex)
        Bu = smp.Bu.copy()
        vr = smp.vertex[rows]
        Bu[rows] = OPTS["ridges"].basis(vr, smp.y[rows], h)[0]
        import dataclasses
        smp = dataclasses.replace(smp, Bu=Bu)        # smp.Bs = Bu / h_v^|m| follows
    return _old(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints, mu=mu)


# ------------------------------------------------------------ patches of the evaluation
def corner_terms(model, n, faces, xb, nu, degree=None, _old=ev.corner_terms):
    """evaluate.corner_terms with the slots' vertices known to :func:`eval_monomials`."""
    topo = model.topology
    u = topo.face_vertices[topo.face_offsets[faces][None, :] + np.arange(n)[:, None]]
    OPTS["eval_u"] = np.broadcast_to(u[:, :, None], (n,) + xb.shape[:2])
    try:
        return _old(model, n, faces, xb, nu, degree)
    finally:
        OPTS["eval_u"] = None


def eval_monomials(y, degree, nu=0, _old=monomials):
    """The corner terms' monomials (chart derivatives), the ridge vertices' slots replaced."""
    mm = _old(y, degree, nu)
    ub = OPTS.get("eval_u")
    if OPTS["index"] is None or ub is None or degree != 4 or ub.shape != y.shape[:-1]:
        return mm
    sel = OPTS["ridges"].at[ub] >= 0
    if sel.any():
        got = OPTS["ridges"].basis(ub[sel], y[sel], OPTS["rings_h"], nu)
        for k in range(nu + 1):
            mm[k][sel] = got[k]
    return mm


def write_mono(data_e, cols_e, e0, y, w, vertex, Mt, _old=asm._write_mono):
    _old(data_e, cols_e, e0, y, w, vertex, Mt)
    if OPTS["index"] is None:
        return
    rows = _ridge_rows(vertex)
    if not len(rows):
        return
    ptr = np.zeros(len(w) + 1, dtype=np.int64)
    np.cumsum(Mt, out=ptr[1:])
    B = OPTS["ridges"].basis(vertex[rows], y[rows], OPTS["rings_h"])[0]
    pos = e0 + ptr[rows][:, None] + np.arange(MM)
    data_e[pos] = B * w[rows][:, None]


def fair_fits(topo, charts, corners2d, cover, rings, X, rule, sharp=None, constraints=None,
              _old=ag.fair_fits):
    OPTS["ctx"] = (topo, charts, corners2d, X)
    OPTS["index"], OPTS["ridges"] = None, None
    return _old(topo, charts, corners2d, cover, rings, X, rule, sharp, constraints)


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "fair_fits", fair_fits),
                                 (ag, "candidate_fits_all", candidates),
                                 (ag, "candidate_values", candidate_values),
                                 (ag, "_samples", samples),
                                 (ag, "_fold_penalty", penalty),
                                 (ag, "_choose", choose),
                                 (ag, "first_minimum", first_minimum),
                                 (ag, "coupled_fits", coupled),
                                 (ev, "corner_terms", corner_terms),
                                 (ev, "monomials", eval_monomials),
                                 (asm, "_write_mono", write_mono)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with this module's change."""
    return run_variant(patched, V, F, r, exact=exact, **opts)


def half(V, F, r, exact=True):
    """Variant: half ridges along star edges sharper than 90 degrees, cubic part, delta 0.5,
    cage samples at weight 0.3, gate 0.5."""
    return variant(V, F, r, exact=exact)


def line(V, F, r, exact=True):
    """Variant: line ridges (through v), delta 0.25, no cage samples."""
    return variant(V, F, r, exact=exact, kind="line", delta=0.25, kappa=0.0)


def fold_corners(V, F, r=8, threshold=90.0, rings=0):
    """(V,) bool: the corners of the cage faces holding an output pair above ``threshold``
    degrees on the default surface at resolution r (and ``rings`` rings around them)."""
    from gerbs_core import BlendingSurface
    from shape.folds import fold_sites
    s = BlendingSurface(V, F)
    topo = s.topology
    allow = np.zeros(topo.n_vertices, bool)
    for _, f, _, _, f2 in fold_sites(s, r, threshold):
        for g in (f, f2):
            allow[topo.face_vertices[topo.face_offsets[g]:topo.face_offsets[g + 1]]] = True
    e = np.asarray(topo.edges)
    for _ in range(rings):
        grow = allow.copy()
        grow[e[allow[e[:, 0]], 1]] = True
        grow[e[allow[e[:, 1]], 0]] = True
        allow = grow
    return allow


def targeted(V, F, r, exact=True, **opts):
    """Variant: the half ridges offered only at the corners of the cage faces where the
    default surface has an output pair above 90 degrees at resolution 8 (the rest shape's
    own folds: a function of the rest shape, so the output stays linear in X), gate 0.3."""
    opts.setdefault("gate", 0.3)
    return variant(V, F, r, exact=exact, allow=fold_corners(V, F), **opts)
