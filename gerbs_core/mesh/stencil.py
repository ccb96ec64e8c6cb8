"""Sparse stencils: the tessellated surface as a fixed linear function of the vertex positions.

S(p) = sum_k Psi_k(p) (X_{u_k} + mono(zeta_{u_k}(p)) . c_{u_k}) and the coefficients
c = A X (:mod:`gerbs_core.mesh.agreement`) are linear in the positions X for a
fixed topology and rest shape, so the output points are

    points = B @ X + E @ (A @ X),     B[p, u_k] = Psi_k(p),  E[p, u_k M + m] = Psi_k(p) mono_m,

with B (P, V), E (P, V M) and A (V M, V) sparse. Kept factored: E and A together
hold far fewer entries than their product W = B + E A, whose rows reach every
vertex the coefficients of a face's corners depend on (data rings + coupling
sweeps). Updates cost one product with A (V M rows) and one with E (n M per row).

Locality (exact, tested): moving vertex j changes the coefficients of the vertices
in A's column j and the points of the faces having such a vertex as a corner.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["Stencil"]


def _canonical(m):
    """m as canonical csr (sorted, no duplicates); never modifies the caller's matrix."""
    m = m.tocsr()
    if not m.has_canonical_format:
        m = m.copy()
        m.sum_duplicates()      # also sorts the indices of every row
    return m


def _scatter_add(points, m, values) -> None:
    """points[m.row] += m.data * values[m.col] (summed per row): the hit rows sorted once
    and each column summed by bincount (np.add.at is an order of magnitude slower)."""
    if m.nnz == 0:
        return
    hit, inv = np.unique(m.row, return_inverse=True)
    for k in range(values.shape[1]):
        points[hit, k] += np.bincount(inv, weights=m.data * values[m.col, k],
                                      minlength=len(hit))


class Stencil:
    """The output points of a surface at one resolution as a linear map of the positions.

    Attributes: ``base`` B (P, V), ``mono`` E (P, V M) (csr), ``fits`` the coefficient
    map (:class:`gerbs_core.mesh.coupling.CoupledFits`, c = A X) and ``operator`` A
    (V M, V) (csr, made on first use: a full build needs only ``fits(X)``, partial
    updates need A); ``triangles`` (T, 3), ``vertex_samples`` (V,) the output point of
    each vertex, ``lattice`` (:class:`gerbs_core.mesh.lattice.Lattice`). Immutable; the
    transposes for partial updates are made on first use.
    """

    def __init__(self, base, mono, fits, lattice):
        self.base, self.mono = _canonical(base), _canonical(mono)
        self.fits = fits
        self.lattice = lattice
        self.triangles = lattice.triangles
        self.vertex_samples = lattice.vertex_sample
        self._csc = None

    @property
    def operator(self) -> sp.csr_matrix:
        return self.fits.operator

    @property
    def shape(self) -> tuple[int, int]:
        return self.base.shape

    @property
    def nnz(self) -> int:
        """Stored entries of the three factors."""
        return self.base.nnz + self.mono.nnz + self.operator.nnz

    def apply(self, X) -> np.ndarray:
        """Output points (P, k) for vertex positions X (V, k) (the same sums for every k:
        one column at a time)."""
        X = np.asarray(X, dtype=np.float64)
        if X.ndim == 1:
            return self.base @ X + self.mono @ self.fits(X)
        C = self.fits(X)
        out = np.empty((self.base.shape[0], X.shape[1]))
        for k in range(X.shape[1]):
            xk, ck = np.ascontiguousarray(X[:, k]), np.ascontiguousarray(C[:, k])
            out[:, k] = self.base @ xk + self.mono @ ck
        return out

    def apply_moved(self, points: np.ndarray, moved: np.ndarray, delta: np.ndarray) -> None:
        """points += the change of the output when the vertices ``moved`` (m,) move by
        ``delta`` (m, k), in place, touching only the affected rows (exact up to round-off:
        the same sums regrouped). Needs only the moved vertices' columns of the
        coefficient operator (:meth:`CoupledFits.columns`), never the whole operator."""
        if self._csc is None:
            self._csc = (self.base.tocsc(), self.mono.tocsc())
        Bc, Ec = self._csc
        moved = np.asarray(moved, dtype=np.int64)
        dB = Bc[:, moved]
        # coefficient changes on the rows the moved columns touch only: a dense (V M, k)
        # product would cost the whole mesh on every drag step
        C = self.fits.columns(moved).tocsr()
        rows = np.flatnonzero(np.diff(C.indptr))
        dc = C[rows] @ delta
        keep = np.any(dc != 0, axis=1)
        rows, dc = rows[keep], dc[keep]
        dE = Ec[:, rows]
        _scatter_add(points, dB.tocoo(), delta)
        _scatter_add(points, dE.tocoo(), dc)

    def matrix(self) -> sp.csr_matrix:
        """The explicit W = B + E A (P, V) -- for tests and small meshes; it holds many
        more entries than the factors."""
        return (self.base + self.mono @ self.operator).tocsr()

    def nnz_per_row(self) -> float:
        return self.nnz / max(self.base.shape[0], 1)
