"""Local functions: Taylor polynomials of Hermite data (paper section 2.6, item 1),
local weighted least-squares derivative estimation, and the regularized
(averaged) Taylor polynomial of Lemma 5.

Derivative tensors are stored as a list ``D = [D0, D1, ..., Dm]`` with
``Dk`` of shape (N, V, n, ..., n) (k trailing axes, symmetric), V the flattened
trailing value shape: T_i(x) = sum_k Dk[i] (x - x_i)^k / k!.

Derivative estimation (when gradients/Hessians are not given), per point x_i:

* neighbours: the ``n_neighbors`` nearest other points (cKDTree; default
  ceil(1.8 M) + 2, M = number of unknown coefficients), offsets scaled by
  h_i = distance to the farthest of them: u_j = (x_j - x_i)/h_i;
* model: f(x_j) - [known Taylor terms at x_i] = sum_{alpha unknown} c_alpha u_j^alpha/alpha!
  over all multi-indices with 1 <= |alpha| <= fit_degree not given as data (the
  value f_i is always kept exactly, so interpolation is not affected); when
  gradients are given they are fitted too (equations h_i (grad f(x_j) - known terms));
* weights w_j = (1 - (|u_j| / 1.2)^2)^2 (smooth, positive on the stencil);
* batched normal equations with a tiny relative ridge (1e-12 x trace) for
  degenerate stencils; D^alpha f(x_i) = c_alpha / h_i^|alpha|.

Polynomials of degree <= fit_degree are reproduced exactly (up to rounding).
"""
from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InvalidParameterError, InvalidPointSetError

__all__ = ["multi_indices", "taylor_jet", "estimate_derivatives", "averaged_taylor", "tensors_from_coeffs",
           "coefficient_tables"]


def multi_indices(n, kmin, kmax):
    """Multi-indices alpha (tuples of length n) with kmin <= |alpha| <= kmax, graded."""
    out = []
    for k in range(kmin, kmax + 1):
        for combo in itertools.combinations_with_replacement(range(n), k):
            a = [0] * n
            for c in combo:
                a[c] += 1
            out.append(tuple(a))
    return out


def _alpha_of(idx_tuple, n):
    a = [0] * n
    for c in idx_tuple:
        a[c] += 1
    return tuple(a)


def tensors_from_coeffs(coeffs, alphas, n, kmax):
    """Symmetric tensors Dk (N, V, n^k) from partial derivatives D^alpha (N, V) per alpha."""
    lookup = {a: c for a, c in zip(alphas, coeffs)}
    N, V = coeffs[0].shape
    out = {}
    for k in range(1, kmax + 1):
        if not any(sum(a) == k for a in alphas):
            continue
        T = np.zeros((N, V) + (n,) * k)
        for idx in itertools.product(range(n), repeat=k):
            T[(slice(None), slice(None)) + idx] = lookup[_alpha_of(idx, n)]
        out[k] = T
    return out


def taylor_jet(D, d, nu):
    """Value, gradient, Hessian of T(x) = sum_k Dk (d)^k / k! at offsets d = x - x_i.

    ``D[k]`` has shape (..., V, n^k) broadcast-compatible with d (..., n).
    Returns value (..., V), gradient (..., V, n), Hessian (..., V, n, n).
    Each contraction with d is one matmul over the last axis, so the temporaries
    are never larger than D[k] itself.
    """
    m = len(D) - 1
    n = d.shape[-1]
    v = D[0].copy()
    g = np.zeros(v.shape + (n,)) if nu >= 1 else None
    h = np.zeros(v.shape + (n, n)) if nu >= 2 else None
    lead = np.broadcast_shapes(v.shape[:-1], d.shape[:-1])
    if g is not None:
        g = np.broadcast_to(g, lead + g.shape[-2:]).copy()
    if h is not None:
        h = np.broadcast_to(h, lead + h.shape[-3:]).copy()
    for k in range(1, m + 1):
        A = D[k]
        partial = [A]
        for _ in range(k):
            # d as a column (..., 1, ..., 1, n, 1) against A's trailing axis
            col = d.reshape(d.shape[:-1] + (1,) * (A.ndim - d.ndim) + (n, 1))
            A = np.matmul(A[..., None, :], col)[..., 0, 0]
            partial.append(A)
        # partial[j]: D_k with j axes contracted -> (k - j) free axes
        v = v + partial[k] / math.factorial(k)
        if nu >= 1:
            g = g + partial[k - 1] / math.factorial(k - 1)
        if nu >= 2 and k >= 2:
            h = h + partial[k - 2] / math.factorial(k - 2)
    return v, g, h


def _default_neighbors(M):
    return int(math.ceil(1.8 * M)) + 2


def _monomials(pw, alphas, fact):
    """u^alpha / alpha! as a contiguous (c, M, K) array (one row per alpha), from the
    powers pw[k] = u^k (k >= 1) of shape (n, c, K) (pw[0] unused).

    Factors u_k^0 = 1 are skipped, not multiplied (exact either way), and the last
    product is written in place: about half the passes of the plain products."""
    shape = pw[1].shape
    out = np.empty(shape[1:2] + (len(alphas),) + shape[2:])
    for j, a in enumerate(alphas):
        dst = out[:, j, :]
        live = [k for k in range(len(a)) if a[k]]
        inv = 1.0 / fact[j]
        if not live:
            dst[...] = inv
            continue
        m = inv
        for i, k in enumerate(live):
            m = np.multiply(pw[a[k]][k], m, out=dst if i == len(live) - 1 else None)
    return out


def estimate_derivatives(points, D_known, fit_degree, n_neighbors=None, tree=None, chunk=None,
                         work_bytes=128e6):
    """Estimate partial derivatives of orders known+1 .. fit_degree at every point.

    ``D_known`` = [values (N, V), gradients (N, V, n)?, Hessians (N, V, n, n)?] as given
    (known = len(D_known) - 1). Neighbour values, and neighbour gradients when given,
    are fitted after subtracting the known Taylor terms at x_i.
    ``tree``: a cKDTree of ``points`` to reuse; the points are processed in chunks whose
    working arrays take about ``work_bytes`` (or ``chunk`` points at a time).
    Returns a dict k -> tensor (N, V, n^k) for k = known+1 .. fit_degree.
    """
    N, n = points.shape
    known = len(D_known) - 1
    alphas = multi_indices(n, known + 1, fit_degree)
    M = len(alphas)
    if M == 0:
        return {}
    K = _neighbour_count(N, n, M, fit_degree, n_neighbors)
    tree = cKDTree(points) if tree is None else tree
    V = D_known[0].shape[1]
    if chunk is None:
        rows = K * (1 + (n if known >= 1 else 0))
        per_point = 8 * (rows * (3 * M + 2 * V + 3 * n + 4) + M * (M + V) * 3)
        # a chunk's working arrays stay cache-sized (~8 MB, ~1000 points in the plane:
        # measured fastest at 4,004 and 10^5 points, 2x larger ones as fast warm but 3 ms
        # slower on a first call (page faults), 10x larger ones 2x slower)
        chunk = int(max(64, min(N, work_bytes // per_point, 8e6 // per_point)))
    # D^alpha f = c_alpha / h^|alpha|: the powers of each order once per point, then
    # gathered per alpha (the same pow calls as per alpha, a third of them in the plane)
    orders = np.arange(known + 1, fit_degree + 1, dtype=float)
    which = np.array([sum(a) for a in alphas]) - (known + 1)
    # visit the points in the tree's own order (its leaves' order): neighbouring
    # queries share the tree's paths and the gathered rows (k-NN 25 % faster at 10^5)
    visit = tree.indices if len(tree.indices) == N else np.arange(N)
    out_coeffs = np.empty((M, N, V))
    for s in range(0, N, chunk):
        rows = visit[s:s + chunk]
        dist, nb = tree.query(points[rows], k=K + 1)
        h = dist[:, -1]
        c = _fit_chunk(points, D_known, rows, nb[:, 1:], h, alphas, fit_degree)
        hk = (h[:, None, None] ** orders[None, :, None])[:, which]            # (c, M, 1)
        out_coeffs[:, rows, :] = (c / hk).transpose(1, 0, 2)
    return tensors_from_coeffs(list(out_coeffs), alphas, n, fit_degree)


def _neighbour_count(N, n, M, fit_degree, n_neighbors):
    """The stencil size K for M unknown coefficients, checked against the data."""
    K = _default_neighbors(M) if n_neighbors is None else int(n_neighbors)
    if K < M:
        raise InvalidParameterError("n_neighbors", f"need >= {M} neighbours for fit_degree {fit_degree}")
    if N - 1 < M:
        raise InvalidPointSetError(
            f"points: {N} points are too few to estimate derivatives up to order {fit_degree} "
            f"in n={n} (need at least {M + 1}); give derivatives or lower the degree")
    return min(K, N - 1)


def _fit_chunk(points, D_known, rows, nb, h, alphas, fit_degree):
    """The scaled coefficients c_alpha (c, M, V) of the points ``rows`` (c,) from their neighbours
    nb (c, K), h (c,) the farthest neighbour's distance (module docstring's model)."""
    A, B, W = _equations(points, D_known, rows, nb, h, alphas, fit_degree)
    At = np.concatenate(A, axis=2) if len(A) > 1 else A[0]                 # (c, M, rows)
    B = np.concatenate(B, axis=1)
    W = np.concatenate(W, axis=1)
    AWt = At * W[:, None, :]                                               # (c, M, rows)
    # batched normal equations: each 2-D slice is BLAS-able (contiguous / transposed)
    G = np.matmul(AWt, np.swapaxes(At, 1, 2))
    M = G.shape[1]
    tr = np.trace(G, axis1=1, axis2=2)
    diag = G.reshape(len(G), M * M)[:, :: M + 1]      # a view of the diagonals
    diag += (1e-12 * tr / M)[:, None]
    return np.linalg.solve(G, np.matmul(AWt, B))                           # (c, M, V)


def _equations(points, D_known, rows, nb, h, alphas, fit_degree):
    """Weighted least-squares equations of the points ``rows`` (c,): lists of design blocks
    (c, M, K), right-hand sides (c, K, V) and weights (c, K): the values, then (with
    known gradients) one block per gradient component."""
    n = points.shape[1]
    known = len(D_known) - 1
    expo = np.array(alphas, dtype=float)                                   # (M, n)
    fact = np.array([math.prod(math.factorial(a) for a in al) for al in alphas], dtype=float)
    # offsets and u = dx / h coordinate-major (n, c, K): contiguous gathers and rows
    pt = np.ascontiguousarray(points[rows].T)
    dxt = np.stack([points[:, k][nb] - pt[k][:, None] for k in range(n)])
    ut = dxt / h[None, :, None]
    r2 = ut[0] * ut[0]
    for k in range(1, n):
        r2 += ut[k] * ut[k]
    w = (1.0 - (np.sqrt(r2) / 1.2) ** 2) ** 2
    if known >= 1:
        Dloc = [Dk[rows, None] for Dk in D_known]                           # broadcast over K
        Tv, Tg, _ = taylor_jet(Dloc, np.ascontiguousarray(np.moveaxis(dxt, 0, -1)), 1)
    else:
        Tv = D_known[0][rows, None]                                        # T = f(x_i)
    pw = [None, ut]
    for _ in range(fit_degree - 1):
        pw.append(pw[-1] * ut)                                             # u^k per coordinate
    A = [_monomials(pw, alphas, fact)]                                     # (c, M, K)
    B = [D_known[0][nb] - Tv]                                              # (c, K, V)
    W = [w]
    if known >= 1:
        # gradient equations: h (grad f(x_j) - grad T_known(x_j)) = sum c_a d/du_l (u^a/a!)
        for l in range(n):
            dal = [tuple(a[k] - (k == l) if a[k] > 0 or k != l else 0 for k in range(n)) for a in alphas]
            coef = expo[:, l]
            A.append(coef[None, :, None] * _monomials(pw, dal, fact))
            B.append(h[:, None, None] * (D_known[1][nb][..., l] - Tg[..., l]))
            W.append(w)
    return A, B, W


def averaged_taylor(func_jet, centers, radii, degree, n_quad=8):
    """Regularized Taylor coefficients of Lemma 5 over balls D = B(x_i, r_i).

    Q f(x) = int_D g(y) sum_{|alpha| <= degree} D^alpha f(y) (x - y)^alpha / alpha! dy,
    g = 1/|D| on D (eq. (48); our ``degree`` is the paper's m - 1). Re-expanded
    about x_i, Q f is a polynomial of degree ``degree`` whose derivative tensors at
    x_i are returned like the data tensors of :func:`taylor_jet`. Needs the
    derivatives of f at the quadrature nodes, so ``func_jet(y (..., n))`` must
    return [f (..., V), grad (..., V, n), Hess (..., V, n, n)] up to ``degree``.

    Quadrature (approximate, exact for polynomials of degree <= 2 n_quad - 1 - ...):
    Gauss-Legendre product rule on the cube [-r, r]^n restricted to the ball by
    a polar map in n = 2 (Gauss in r^1 dr, uniform in angle), and a masked tensor
    Gauss rule otherwise (n_quad^n nodes).
    """
    centers = np.asarray(centers, float)
    N, n = centers.shape
    radii = np.broadcast_to(np.asarray(radii, float), (N,))
    if degree > 2:
        raise InvalidParameterError("degree", "averaged Taylor coefficients need degree <= 2")
    if n == 2:
        t, wt = np.polynomial.legendre.leggauss(n_quad)
        rr = 0.5 * (t + 1.0)
        wr = 0.5 * wt * rr                                    # int_0^1 r dr
        na = 2 * n_quad + 1
        ang = 2 * np.pi * np.arange(na) / na
        nodes = (rr[:, None, None] * np.stack([np.cos(ang), np.sin(ang)], -1)[None]).reshape(-1, 2)
        wq = np.repeat(wr, na) * (2 * np.pi / na) / np.pi     # normalised by |unit disc|
    else:
        t, wt = np.polynomial.legendre.leggauss(n_quad)
        grid = np.array(list(itertools.product(t, repeat=n)))
        wgrid = np.prod(np.array(list(itertools.product(wt, repeat=n))), axis=1)
        inside = np.linalg.norm(grid, axis=1) <= 1.0
        nodes, wq = grid[inside], wgrid[inside]
        wq = wq / wq.sum()
    y = centers[:, None, :] + radii[:, None, None] * nodes[None]          # (N, Q, n)
    jets = func_jet(y)
    # Taylor polynomial of f at y re-expanded at x_i: derivatives at x_i of
    # P_y(x) = sum_k D^k f(y)(x - y)^k/k!: the j-th derivative is sum_{k>=j} D^k f(y)(x_i - y)^{k-j}/(k-j)!
    d = centers[:, None, :] - y                                            # x_i - y
    out = []
    for j in range(degree + 1):
        acc = 0.0
        for k in range(j, degree + 1):
            A = jets[k]
            for _ in range(k - j):
                A = np.sum(A * d.reshape(d.shape[:-1] + (1,) * (A.ndim - d.ndim) + (n,)), axis=-1)
            acc = acc + A / math.factorial(k - j)
        out.append(np.einsum("q,nq...->n...", wq, acc))
    return out


def coefficient_tables(D, n, nu):
    """Monomial coefficients of T_i and of its first and second derivatives.

    D = [D0 (N, V), D1 (N, V, n), ..., Dm (N, V, n^m)] (symmetric derivative tensors).
    Returns [C0 (N, V, Q_m), C1 (N, V, n, Q_{m-1}), C2 (N, V, n, n, Q_{m-2})][: nu + 1]
    with T_i(x) = C0 . d^alpha, d_l T_i = C1[:, :, l] . d^beta, d_l d_k T_i =
    C2[:, :, l, k] . d^gamma (d = x - x_i, monomials as in
    :func:`gerbs_core.scattered.local_sums.monomials`).
    Exact: C_alpha = D^alpha f(x_i) / alpha!.
    """
    m = len(D) - 1
    N, V = D[0].shape

    def table(shift):
        """Coefficients of the derivative d^shift T (shift a multi-index)."""
        alphas = multi_indices(n, 0, max(m - sum(shift), -1)) if m >= sum(shift) else []
        C = np.zeros((N, V, max(len(alphas), 1)))
        for q, b in enumerate(alphas):
            a = tuple(bi + si for bi, si in zip(b, shift))
            k = sum(a)
            idx = tuple(c for c in range(n) for _ in range(a[c]))
            fact = float(np.prod([math.factorial(x) for x in b]))
            C[:, :, q] = D[k][(slice(None), slice(None)) + idx] / fact
        return C

    zero = (0,) * n
    out = [table(zero)]
    if nu >= 1:
        e = np.eye(n, dtype=int)
        out.append(np.stack([table(tuple(e[l])) for l in range(n)], axis=2))
    if nu >= 2:
        out.append(np.stack([np.stack([table(tuple(e[l] + e[k])) for k in range(n)], axis=2)
                             for l in range(n)], axis=2))
    return out
