"""Prototype: a GRADIENT tension in the coupling at sharp faces.

Without the coupling sweeps Suzanne's mouth corners do not fold (0 pairs above 90
degrees at 139 / 140; 2 sweeps: 4 pairs, 117 degrees): the agreement term of the coupling
bends the local functions there. The value tension (lam s_f P |l - C|^2) keeps l near
the cage point but lets it tilt. This variant adds to every sweep's energy

    lam_g h_v^2 sum_rows w s_f P |dl_v/dx(p) - A_f|^2,

dl_v/dx the local function's derivative in p's face layout coordinates and A_f (3, 2) the
least-squares affine map of the face's layout corners onto their positions (exact on
triangles): a pull of the local function's tangent plane towards the cage face's where
the face is sharp (s_f, as the value tension). A_f is linear in X and the rows' matrices
are fixed by the rest shape, so the coefficients stay a linear map of X (constants: A_f =
0, zero coefficients). The choice is unchanged; the term enters the coupling through the
chosen fits' normal matrices and right-hand sides, which every sweep reuses. Measured in docs/design.md ("Folds")."""
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
from shape.proto.blend_fold import row_jets  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
from gerbs_core.mesh.monomials import monomial_exponents, monomials, n_monomials  # noqa: E402

OPTS = {"lam_g": 1.0, "g_from": None, "g_to": None, "ctx": None, "inner": None, "inner_fair": None, "ridges": False}


def face_gradients(topo, corners2d):
    """csr (2 F, V): row 2 f + j maps positions X to column j of A_f, the least-squares
    affine map of face f's layout corners onto X (exact on triangles)."""
    rows, cols, vals = [], [], []
    for n in np.unique(topo.face_sizes).tolist():
        fs = np.flatnonzero(topo.face_sizes == n)
        c = topo.face_offsets[fs][:, None] + np.arange(n)               # (F_n, n)
        L = corners2d[c] - corners2d[c].mean(1, keepdims=True)          # (F_n, n, 2)
        G = L @ np.linalg.inv(np.swapaxes(L, 1, 2) @ L)                 # (F_n, n, 2)
        for j in range(2):
            rows.append(np.repeat(2 * fs + j, n))
            cols.append(topo.face_vertices[c].ravel())
            vals.append(G[:, :, j].ravel())
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(2 * topo.n_faces, topo.n_vertices))


def coupled(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints=None, mu=None,
            _old=ag.coupled_fits):
    """ag.coupled_fits with the gradient term: its normal matrices added to the chosen fits'
    (``normals``, block diagonal per vertex) and its right-hand side to theirs (``rhs``),
    both of which every sweep reuses."""
    if OPTS["inner"] is not None:      # the ridge prototype's coupling (with_ridges)
        _old = OPTS["inner"]
    if not OPTS["lam_g"] or not (rule.sweeps and (rule.mu or rule.lam)):
        return _old(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints, mu=mu)
    topo, charts, corners2d, cover, X = OPTS["ctx"]
    sharp = smp.sharp
    if OPTS["g_from"] is not None:     # its own sharpness ramp (degrees), not the tension's
        sharp = ag.face_sharpness(topo, X, OPTS["g_from"], OPTS["g_to"])[smp.face]
    V, mmax = len(degrees), n_monomials(dmax)
    deg = monomial_exponents(dmax).sum(1)
    _, J = row_jets(topo, charts, corners2d, cover, smp, rule.resolution)
    dm = monomials(smp.y, dmax, 1)[1]
    if OPTS["ridges"]:                 # the ridge vertices' basis (ridges prototype)
        from shape.proto import ridges as R
        if R.OPTS["index"] is not None:
            rows = R._ridge_rows(smp.vertex)
            dm[rows] = R.OPTS["ridges"].basis(smp.vertex[rows], smp.y[rows], h, 1)[1]
    dm = np.einsum("smi,sij->smj", dm, J)                                # (SC, M, 2) d/dx
    dBs = dm / (h[smp.vertex][:, None] ** deg[None, :])[..., None]
    active = (np.arange(mmax)[None, :]
              < np.array([n_monomials(d) for d in degrees])[smp.vertex][:, None])
    SC = len(smp.vertex)
    wg = OPTS["lam_g"] * smp.weight * sharp * smp.psi * h[smp.vertex] ** 2
    # the rows (2 SC): row 2 s + j is d/dx_j at row s
    r2 = np.repeat(np.arange(SC)[:, None] * 2, mmax, 1)
    cols = smp.vertex[:, None] * mmax + np.arange(mmax)
    Bd = sp.csr_matrix((np.concatenate([dBs[..., 0][active], dBs[..., 1][active]]),
                        (np.concatenate([r2[active], r2[active] + 1]),
                         np.concatenate([cols[active], cols[active]]))), shape=(2 * SC, V * mmax))
    W = sp.diags(np.repeat(wg, 2))
    target = face_gradients(topo, corners2d)[
        (2 * smp.face[:, None] + np.arange(2)).ravel()]                  # (2 SC, V)
    BdT = Bd.T.tocsr()
    Ng = (BdT @ W @ Bd).tocoo()
    N = normals.copy()
    N[Ng.row // mmax, Ng.row % mmax, Ng.col % mmax] += Ng.data
    return _old(chosen, rhs + BdT @ W @ target, N, degrees, smp, rule, h, dmax, constraints)


def fair_fits(topo, charts, corners2d, cover, rings, X, rule, sharp=None, constraints=None,
              _old=ag.fair_fits):
    OPTS["ctx"] = (topo, charts, corners2d, cover, X)
    if OPTS["inner_fair"] is not None:     # the ridge prototype's (with_ridges)
        _old = OPTS["inner_fair"]
    return _old(topo, charts, corners2d, cover, rings, X, rule, sharp, constraints)


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "fair_fits", fair_fits), (ag, "coupled_fits", coupled)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with this module's change."""
    return run_variant(patched, V, F, r, exact=exact, **opts)


def g1(V, F, r, exact=True):
    """Variant: gradient tension lam_g = 1."""
    return variant(V, F, r, exact=exact, lam_g=1.0)


def g03(V, F, r, exact=True):
    """Variant: gradient tension lam_g = 0.3."""
    return variant(V, F, r, exact=exact, lam_g=0.3)


def with_ridges(V, F, r, exact=True, **opts):
    """Variant: gradient tension lam_g = 1 and the ridge candidates of
    scripts/shape/proto/ridges.py (half ridges, its defaults)."""
    from contextlib import ExitStack
    from shape import methods
    from shape.proto import ridges as R
    ropts = {k: opts.pop(k) for k in list(opts) if k in R.OPTS}
    with ExitStack() as st:
        st.enter_context(R.patched(**ropts))
        st.enter_context(patched(inner=R.coupled, inner_fair=R.fair_fits, ridges=True, **opts))
        return methods.gerbs_samples(V, F, r, exact=exact)


def g1s80(V, F, r, exact=True):
    """Variant: gradient tension lam_g = 1 on faces sharp from 80 to 120 degrees."""
    return variant(V, F, r, exact=exact, lam_g=1.0, g_from=80.0, g_to=120.0)


def g1s90(V, F, r, exact=True):
    """Variant: gradient tension lam_g = 1 on faces sharp from 90 to 120 degrees."""
    return variant(V, F, r, exact=exact, lam_g=1.0, g_from=90.0, g_to=120.0)
