"""Data rings and pinned fits of the local functions (gerbs_core.mesh.rings / .fits)."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.mesh.charts import vertex_charts
from gerbs_core.mesh.fits import (CANDIDATES, candidate_fits, candidate_fits_all,
                                  pinned_normal_inverse)
from gerbs_core.mesh.layout import face_layouts
from gerbs_core.mesh.monomials import (bending_gram, monomial_exponents, monomial_gradients,
                                       monomials, n_monomials)
from gerbs_core.mesh.rings import data_rings
from gerbs_core.mesh.topology import MeshTopology


def _setup(V, F, rest=None):
    topo = MeshTopology(F, len(V))
    sh = face_layouts(topo, V if rest is None else rest)
    ch = vertex_charts(topo, sh.corners, sh.angles, "keep")
    return topo, sh, ch, data_rings(topo, ch, sh.corners)


def _poly(d, rng):
    E = monomial_exponents(d)
    c = rng.normal(size=len(E))
    return lambda x, y: 0.4 + sum(ci * x ** a * y ** b for ci, (a, b) in zip(c, E))


@pytest.mark.parametrize("degree,layers", CANDIDATES)
def test_flat_fits_reproduce_polynomials_of_their_degree(degree, layers):
    V, F = P.delaunay_patch(80, 4)
    rng = np.random.default_rng(degree)
    p = _poly(degree, rng)
    topo, sh, ch, rings = _setup(V, F)
    fits = candidate_fits(rings, degree, layers)
    M = n_monomials(degree)
    Z = p(V[:, 0], V[:, 1])
    C = (fits.matrix @ Z).reshape(len(V), M)
    # vertices whose data determine a polynomial of the degree (full-rank normal matrix)
    ev = np.linalg.eigvalsh(fits.normal)
    determined = ev[:, 0] > 1e-6 * ev[:, -1]
    inner = np.flatnonzero(~topo.vertex_is_boundary & determined)
    assert len(inner) >= (0.5 * (~topo.vertex_is_boundary).sum() if degree < 4 else 5)
    for v in inner:
        c = topo.star_corners[topo.star_offsets[v]]
        n = topo.corner_next[c]
        yn = ch.to_chart(c, sh.corners[n])[0]
        dn = V[topo.face_vertices[n], :2] - V[v, :2]
        rot = complex(*yn) / complex(*dn)  # chart = rotation of the plane about X_v
        assert abs(abs(rot) - 1) < 1e-11
        y = rng.uniform(-0.2, 0.2, size=(5, 2))
        xy = np.array([complex(*t) / rot for t in y])
        want = p(V[v, 0] + xy.real, V[v, 1] + xy.imag)
        got = Z[v] + monomials(y, degree)[0] @ C[v]
        assert np.abs(got - want).max() < 1e-9


def test_fits_are_linear_and_pinned():
    V, F = P.icosphere(1)
    *_, rings = _setup(V, F)
    fits = candidate_fits(rings, 3, 2)
    rng = np.random.default_rng(1)
    A, B = rng.normal(size=len(V)), rng.normal(size=len(V))
    assert np.allclose(fits.matrix @ (2 * A - B), 2 * (fits.matrix @ A) - fits.matrix @ B)
    # a constant field has zero coefficients (the pin carries it)
    assert np.abs(fits.matrix @ np.full(len(V), 3.0)).max() < 1e-12


@pytest.mark.parametrize("mesh", ["suzanne", "mixed", "grid"])
def test_ring1_fallbacks_alias_the_two_ring_fit_bit_for_bit(mesh):
    # with (3, 2) among the rules, (3, 1) takes its fit where it falls back to two layers
    # instead of computing it: it must equal the rule fitted alone (no sharing) bit for
    # bit, and its rows at the aliased vertices must be (3, 2)'s
    V, F = {"suzanne": P.suzanne, "mixed": lambda: P.mixed_mesh(0.3),
            "grid": lambda: P.grid(6)}[mesh]()
    *_, rings = _setup(np.asarray(V, float), F)
    cands = candidate_fits_all(rings, CANDIDATES)
    i, j = CANDIDATES.index((3, 1)), CANDIDATES.index((3, 2))
    alone = candidate_fits(rings, 3, 1)
    assert alone.alias is None
    for part in ("matrix", "rhs"):
        a, b = getattr(cands[i], part).tocsr(), getattr(alone, part).tocsr()
        assert np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
        assert np.array_equal(a.data, b.data)
    assert np.array_equal(cands[i].normal, alone.normal)
    k, same = cands[i].alias
    assert k == j and same.any()
    if mesh == "grid":
        assert same.all()       # ring 1 of a quad grid holds fewer than M + 2 = 11 data
    else:
        assert not same.all()   # some stars fit ring 1 alone: both paths are exercised
    M = n_monomials(3)
    rows = (np.flatnonzero(same)[:, None] * M + np.arange(M)).ravel()
    for part in ("matrix", "rhs"):
        a, b = getattr(cands[i], part).tocsr()[rows], getattr(cands[j], part).tocsr()[rows]
        assert (a != b).nnz == 0
    assert np.array_equal(cands[i].normal[same], cands[j].normal[same])
    assert all(c.alias is None for c in cands if c is not cands[i])


def test_rings_do_not_depend_on_the_face_order_or_the_star_start():
    V, F = P.suzanne()
    _, _, _, r = _setup(V, F)
    rng = np.random.default_rng(3)
    perm = rng.permutation(len(F))
    F2 = [list(np.roll(F[i], rng.integers(len(F[i])))) for i in perm]
    _, _, _, r2 = _setup(V, F2)

    def as_sets(rr, v):
        a, b = rr.offsets[v], rr.offsets[v + 1]
        d = np.hypot(rr.y[a:b, 0], rr.y[a:b, 1])   # rotation-invariant
        return sorted(zip(rr.ids[a:b].tolist(), rr.ring[a:b].tolist(), np.round(d, 9).tolist()))
    for v in range(len(V)):
        assert as_sets(r, v) == as_sets(r2, v)


def test_cube_corner_unfoldings_are_separate_data():
    # the opposite corner of a cube is reached through its three faces, each unfolded
    # across either of its two edges with the star: six data, all far from the vertex
    # (a mean of them would sit at the vertex itself and wreck the fit)
    V = np.array([(x, y, z) for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
    F = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    *_, r = _setup(V, F)
    a, b = r.offsets[0], r.offsets[1]
    far = r.ids[a:b] == 7
    assert far.sum() == 6 and np.all(np.hypot(*r.y[a:b][far].T) > 2.0)


def test_smoothest_minimiser_is_rotation_invariant():
    # a degenerate data set (collinear points): the fit must not depend on the chart rotation
    t = np.linspace(-1, 1, 7)
    pts = np.stack([t, 0.3 * t], 1)
    vals = 0.5 * t - 0.2 * t ** 2
    outs = []
    for ang in (0.0, 0.7, 2.1):
        R = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
        y = pts @ R.T
        B = monomials(y, 2)[0]
        c = pinned_normal_inverse((B.T @ B)[None], 2)[0] @ (B.T @ vals)
        probe = np.array([[0.3, 0.5], [-0.4, 0.2]]) @ R.T
        outs.append(monomials(probe, 2)[0] @ c)
    assert np.allclose(outs[0], outs[1], atol=1e-10) and np.allclose(outs[0], outs[2], atol=1e-10)


def test_bending_gram_is_rotation_invariant_and_definite():
    for d in (2, 3, 4):
        G = bending_gram(d)
        assert np.all(np.linalg.eigvalsh(G) > 0)
        assert np.isclose(G[2, 2], 4 * np.pi)     # int over the disc of |D^2 x^2|^2
        ang = 0.9
        R = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
        # the rotated monomial basis spans the same space: the Gram's invariants agree
        y = np.random.default_rng(0).normal(size=(60, 2))
        A = np.linalg.lstsq(monomials(y, d)[0], monomials(y @ R.T, d)[0], rcond=None)[0]
        assert np.allclose(np.sort(np.linalg.eigvalsh(A.T @ G @ A)), np.sort(np.linalg.eigvalsh(G)),
                           rtol=1e-8)


@pytest.mark.parametrize("degree", [2, 3, 4])
def test_certified_inverse_is_the_pinned_inverse_to_rounding(degree):
    """Cholesky-certified inverses equal the truncated pseudo-inverses to rounding where
    nothing is truncated, and defer to them where something is: a rank-deficient matrix
    in a stack (the Cholesky of the stack fails) and an ill-conditioned one (the
    certificate fails) give exactly the eigendecomposition's pseudo-inverses."""
    rng = np.random.default_rng(degree)
    M = n_monomials(degree)
    B = rng.normal(size=(40, 3 * M, M))
    N = np.swapaxes(B, 1, 2) @ B
    ref = pinned_normal_inverse(N, degree)
    got = pinned_normal_inverse(N, degree, certified=True)
    assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max()
    low = N.copy()
    low[3] = np.outer(B[3, 0], B[3, 0])                  # rank 1: truncated
    assert np.array_equal(pinned_normal_inverse(low, degree, certified=True),
                          pinned_normal_inverse(low, degree))
    Q, _ = np.linalg.qr(rng.normal(size=(M, M)))
    bad = N.copy()
    bad[5] = (Q * np.geomspace(1.0, 1e-7, M)) @ Q.T     # definite, condition 1e7
    out = pinned_normal_inverse(bad, degree, certified=True)
    assert np.array_equal(out[5], pinned_normal_inverse(bad[5:6], degree)[0])
    assert np.abs(out[:5] - ref[:5]).max() <= 1e-12 * np.abs(ref).max()


@pytest.mark.parametrize("degree", [1, 2, 3, 4])
def test_monomial_gradients_are_the_monomials_derivatives_bit_for_bit(degree):
    y = np.random.default_rng(degree).normal(size=(300, 2))
    y[:3] = [[0.0, 0.0], [-0.0, 1.5], [2.0, -0.0]]          # zeros, signed zeros
    d = monomials(y, degree, 1)[1]
    g = monomial_gradients(y, degree)
    assert g.shape == (2, 300, n_monomials(degree))
    for j in (0, 1):
        assert np.array_equal(g[j], d[..., j])
        assert np.array_equal(np.signbit(g[j]), np.signbit(d[..., j]))


def _grid_with_boundary(n):
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.stack([x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel()) * np.cos(2 * y.ravel())], 1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = (idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(),
                  idx[1:, :-1].ravel())
    return V, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def test_rows_of_compact_and_coordinate_chunks_are_those_of_all_coordinates(monkeypatch):
    """fits._block_rows writes the compact chunks' rows straight into csr and only the
    chunks with a vertex reached twice (a boundary's unfolded rings) as coordinates: the
    matrices equal, bit for bit, those of giving every chunk to scipy as coordinates (the
    rule before, 3.1 -> ~0.4 s on a 35k-vertex height field whose 2 of 35 chunks had
    repeats). Small chunks make a 14x14 grid mix both kinds (asserted: else the check
    would not look at the mix)."""
    import scipy.sparse as sp

    from gerbs_core.mesh import fits as fm

    seen = []
    real = fm._block_rows
    monkeypatch.setattr(fm, "CHUNK_DATA", 256)
    monkeypatch.setattr(fm, "_block_rows",
                        lambda blocks, V, M: seen.append((list(blocks), V, M)) or real(blocks, V, M))
    V, F = _grid_with_boundary(14)
    rings = _setup(V, F)[3]
    candidate_fits_all(rings, CANDIDATES)
    kinds = {len(b) for blocks, _, _ in seen for b in blocks}
    assert kinds == {4, 6}
    for blocks, nv, M in seen:
        parts = [b if len(b) == 4 else fm._coo_rows(b[0], b[3][:, :-1] < b[2][:, None],
                                                     fm._data_ids(b), b[4], b[5])
                 for b in blocks]
        if not parts:
            continue
        rows, cols = (np.concatenate([p[i] for p in parts]) for i in (0, 1))
        ref = [sp.csr_matrix((np.concatenate([p[i] for p in parts]), (rows, cols)),
                             shape=(nv * M, nv)) for i in (2, 3)]
        for got, want in zip(real(blocks, nv, M), ref):
            assert got.has_canonical_format and want.has_canonical_format
            assert np.array_equal(got.indptr, want.indptr)
            assert np.array_equal(got.indices, want.indices)
            assert np.array_equal(got.data, want.data)
