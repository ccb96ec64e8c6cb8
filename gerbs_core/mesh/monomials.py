"""Monomials of the local functions l_v(y) = X_v + sum_m c_m y^m (chart coordinates y).

The monomials y1^a y2^b with 1 <= a + b <= degree, in graded order (degree 1
first, then 2, ...), so that the coefficients of a lower degree are a prefix of
those of a higher one: local functions of different degrees share one padded
coefficient array.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["monomial_exponents", "monomials", "n_monomials", "powers", "bending_gram"]


@lru_cache(maxsize=None)
def _exponents(degree: int) -> np.ndarray:
    e = np.array([(k - j, j) for k in range(1, degree + 1) for j in range(k + 1)],
                 dtype=np.int64).reshape(-1, 2)
    e.flags.writeable = False
    return e


def monomial_exponents(degree: int) -> np.ndarray:
    """Exponents (M, 2) of the monomials of total degree 1..degree (graded order)."""
    return _exponents(int(degree))


def n_monomials(degree):
    """M = degree (degree + 3) / 2, the number of monomials of degree 1..degree (an int,
    or an int array for an array of degrees)."""
    if np.ndim(degree):
        d = np.asarray(degree, dtype=np.int64)
        return d * (d + 3) // 2
    return int(degree) * (int(degree) + 3) // 2


def powers(t: np.ndarray, degree: int) -> list:
    """[1, t, t^2, ..., t^degree] of an array t (each power one product from the last:
    the factors every monomial evaluator multiplies)."""
    out = [np.ones_like(t)]
    for _ in range(int(degree)):
        out.append(out[-1] * t)
    return out


def monomial_gradients(y: np.ndarray, degree: int) -> np.ndarray:
    """(2, N, M): d/dy1 then d/dy2 of the monomials at chart points y (N, 2), bit for bit
    ``monomials(y, degree, 1)[1]``'s two slices, each written contiguously (the rows of
    both derivatives stacked, as one product with the coefficients takes them)."""
    y = np.asarray(y, dtype=np.float64)
    d = np.zeros((2, len(y), n_monomials(degree)))
    _write_gradients(powers(y[:, 0], degree), powers(y[:, 1], degree), degree, d[0], d[1])
    return d


def _write_gradients(p1, p2, degree: int, d1, d2) -> None:
    """The monomials' d/dy1 and d/dy2 into d1, d2 (..., M) (zero-filled; views of any
    layout) from the powers p1, p2 of the two chart coordinates: (a p1^(a-1)) p2^b and
    (b p1^a) p2^(b-1), the one formula of :func:`monomials` and
    :func:`monomial_gradients`."""
    col = np.empty(np.shape(p1[0]))
    for i, (a, b) in enumerate(monomial_exponents(degree)):
        if a:
            np.multiply(p1[a - 1], float(a), out=col)
            np.multiply(col, p2[b], out=d1[..., i])
        if b:
            np.multiply(p1[a], float(b), out=col)
            np.multiply(col, p2[b - 1], out=d2[..., i])


def monomials(y: np.ndarray, degree: int, nu: int = 0):
    """Monomials of chart points y (..., 2) and their derivatives, exact.

    Returns [m (..., M), dm (..., M, 2), d2m (..., M, 2, 2)] up to order nu.
    """
    y = np.asarray(y, dtype=np.float64)
    E = monomial_exponents(degree)
    M = len(E)
    shape = y.shape[:-1]
    p1, p2 = powers(y[..., 0], degree), powers(y[..., 1], degree)
    m = np.empty(shape + (M,))
    for i, (a, b) in enumerate(E):      # written in place: no M temporaries and stack
        np.multiply(p1[a], p2[b], out=m[..., i])
    out = [m]
    if nu >= 1:
        d = np.zeros(shape + (M, 2))
        _write_gradients(p1, p2, degree, d[..., 0], d[..., 1])
        out.append(d)
    if nu >= 2:
        h = np.zeros(shape + (M, 2, 2))
        for i, (a, b) in enumerate(E):
            if a >= 2:
                h[..., i, 0, 0] = a * (a - 1) * p1[a - 2] * p2[b]
            if b >= 2:
                h[..., i, 1, 1] = b * (b - 1) * p1[a] * p2[b - 2]
            if a and b:
                h[..., i, 0, 1] = h[..., i, 1, 0] = a * b * p1[a - 1] * p2[b - 1]
        out.append(h)
    return out


@lru_cache(maxsize=None)
def bending_gram(degree: int) -> np.ndarray:
    """G (M, M): int over the unit disc of <D^2 m_i, D^2 m_j> (Frobenius), plus
    pi * I on the linear monomials (whose second derivatives vanish).

    A rotation-invariant positive definite metric on the coefficients: the fits
    choose the smoothest polynomial in it when the data do not determine one
    (:func:`gerbs_core.mesh.fits.solve_pinned`), so a fit does not depend on how
    its chart is rotated. Exact (polar quadrature of a polynomial integrand).
    """
    n = 2 * degree + 2
    r, wr = np.polynomial.legendre.leggauss(n)
    r, wr = 0.5 * (r + 1.0), 0.5 * wr                      # [0, 1]
    t = 2 * np.pi * np.arange(4 * n) / (4 * n)             # exact for trig. degree < 4n
    R, T = np.meshgrid(r, t, indexing="ij")
    w = (wr[:, None] * R) * (2 * np.pi / len(t))           # r dr dtheta
    y = np.stack([R * np.cos(T), R * np.sin(T)], -1).reshape(-1, 2)
    H = monomials(y, degree, 2)[2]
    G = np.einsum("p,pmij,pnij->mn", w.ravel(), H, H)
    G[:2, :2] += np.pi * np.eye(2)
    G.flags.writeable = False
    return G
