"""Psi (27), Phi (29)-(30), B (32) and its equivalent forms (33), (35), (36), (67), (73)."""
import numpy as np
import pytest

from gerbs_core.kernels import ERBS
from gerbs_core.scattered.metrics import Euclidean
from gerbs_core.scattered.partition import (basis_33, basis_35, basis_36, general_basis, jmul, jrecip,
                                  minimal_basis, normalize)
from gerbs_core.scattered.radii import auto_R, auto_rho, simplicialization

K = ERBS()
RNG = np.random.default_rng(21)


def families(n, N=25, M=300, rho_fraction=0.5):
    P = RNG.random((N, n))
    m = Euclidean(n)
    R, _ = auto_R(P, m)
    rho = auto_rho(P, m, rho_fraction)
    lam = RNG.dirichlet(np.ones(n + 1), size=M // (n + 1) + 1)          # points of the hull
    simp = simplicialization(P)
    x = np.einsum("tk,tkn->tn", lam, P[simp[RNG.integers(0, len(simp), len(lam))]])
    x = np.concatenate([x, P, P + 0.3 * rho[:, None] / np.sqrt(n)])
    y = x[:, None, :] - P[None]
    psi = m.bump_jet(y, R[None], K, 2)
    phi = m.bump_jet(y, rho[None], K, 2)
    keep = psi[0].sum(1) > 0
    families.at_points = np.flatnonzero(np.all(y[keep] == 0.0, axis=-1).any(axis=1))
    return [tuple(a[keep] for a in psi), tuple(a[keep] for a in phi)]


@pytest.mark.parametrize("n", [1, 2, 3])
def test_general_basis_is_a_convex_partition_of_unity_with_hermite_property(n):
    psi, phi = families(n)
    B = general_basis(phi, psi, 2)
    assert np.max(np.abs(B[0].sum(1) - 1)) <= 1e-14
    assert B[0].min() >= 0 and B[0].max() <= 1
    assert np.abs(B[1].sum(1)).max() <= 1e-12 * max(1, np.abs(B[1]).max())
    assert np.abs(B[2].sum(1)).max() <= 1e-12 * max(1, np.abs(B[2]).max())
    # at x_i: B_j(x_i) = delta_ij with vanishing derivatives (Theorem 1 (3))
    at = families.at_points                    # the rows x = x_i
    assert len(at) == 25
    i = phi[0][at].argmax(1)
    np.testing.assert_array_equal(B[0][at, i], 1.0)
    assert np.abs(B[1][at]).max() == 0 and np.abs(B[2][at]).max() == 0


@pytest.mark.parametrize("n", [1, 2, 3])
def test_equivalent_forms_33_35_36(n):
    psi, phi = families(n)
    B32 = general_basis(phi, psi, 0)[0]
    np.testing.assert_allclose(basis_33(phi[0], psi[0]), B32, rtol=0, atol=1e-15)
    # (35)/(36) need disjoint phi supports (34), which Remark 6's rho guarantees
    assert np.all((phi[0] > 0).sum(1) <= 1)
    np.testing.assert_allclose(basis_35(phi[0], psi[0]), B32, rtol=0, atol=1e-15)
    np.testing.assert_allclose(basis_36(phi[0], psi[0]), B32, rtol=0, atol=1e-15)


def test_35_differs_from_32_when_phi_supports_overlap():
    """The reduction (35) is only valid under (34): with rho = 3x the Remark-6 value the
    forms disagree, while (33) stays equal to (32)."""
    psi, phi = families(2, rho_fraction=1.0)
    assert np.any((phi[0] > 0).sum(1) >= 2)
    B32 = general_basis(phi, psi, 0)[0]
    np.testing.assert_allclose(basis_33(phi[0], psi[0]), B32, rtol=0, atol=1e-15)
    assert np.abs(basis_35(phi[0], psi[0]) - B32).max() > 1e-3


def test_maximal_67_and_minimal_73():
    psi, _ = families(2)
    v = psi[0]
    # (67): B_i = prod_{j<i}(1-phi_j) [1 + prod_{j>=i}(1-phi_j) / sum phi_k] phi_i with phi = psi
    om = 1 - v
    before = np.cumprod(np.concatenate([np.ones((len(v), 1)), om[:, :-1]], 1), 1)
    from_i = np.flip(np.cumprod(np.flip(om, 1), 1), 1)
    B67 = before * (1 + from_i / v.sum(1, keepdims=True)) * v
    np.testing.assert_allclose(general_basis(psi, psi, 0)[0], B67, rtol=0, atol=1e-14)
    # (73): B = Psi = psi / sum psi, also what (32) gives for phi = 0 (Theorem 6)
    zero = tuple(np.zeros_like(a) for a in psi)
    np.testing.assert_allclose(general_basis(zero, psi, 2)[0], minimal_basis(psi, 2)[0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(minimal_basis(psi, 0)[0], v / v.sum(1, keepdims=True), rtol=0, atol=1e-15)


def test_jet_algebra_matches_finite_differences():
    """Product and reciprocal jets (used for (27), (29), (32)) against differences."""
    def fun(x):
        a = (np.sin(x[..., 0]) + 2, np.stack([np.cos(x[..., 0]), 0 * x[..., 0]], -1), None)
        H = np.zeros(x.shape + (2,))
        H[..., 0, 0] = -np.sin(x[..., 0])
        a = (a[0], a[1], H)
        b = (np.exp(x[..., 1]) * x[..., 0], np.stack([np.exp(x[..., 1]), x[..., 0] * np.exp(x[..., 1])], -1), None)
        Hb = np.zeros(x.shape + (2,))
        Hb[..., 0, 1] = Hb[..., 1, 0] = np.exp(x[..., 1])
        Hb[..., 1, 1] = x[..., 0] * np.exp(x[..., 1])
        b = (b[0], b[1], Hb)
        return jmul(a, jrecip(b, 2), 2)
    x = 0.5 + RNG.random((20, 2))
    v, g, H = fun(x)
    h = 1e-6
    for k in range(2):
        e = np.zeros(2)
        e[k] = h
        np.testing.assert_allclose((fun(x + e)[0] - fun(x - e)[0]) / (2 * h), g[:, k], rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose((fun(x + e)[1] - fun(x - e)[1]) / (2 * h), H[:, :, k], rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(normalize((v[:, None], g[:, None], H[:, None]), 2)[0], 1.0)
