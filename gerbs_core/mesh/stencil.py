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

from ..errors import InvalidParameterError
from ..immutable import Immutable
from .validation import check_finite

__all__ = ["Stencil"]


def _canonical(m):
    """m as canonical csr (sorted, no duplicates); never modifies the caller's matrix."""
    m = m.tocsr()
    if not m.has_canonical_format:
        m = m.copy()
        m.sum_duplicates()      # also sorts the indices of every row
    return m


def _positions(X, V: int) -> np.ndarray:
    """X as float64 (V,) or (V, k), finite; else the errors of :meth:`Stencil.apply`."""
    try:
        X = np.asarray(X, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError("X", f"must be a real ({V}, k) array of vertex positions, "
                                    f"got {type(X).__name__}") from None
    if X.ndim > 2:
        raise InvalidParameterError("X", f"must be a ({V},) or ({V}, k) array of vertex "
                                    f"positions, got {X.ndim} axes (shape {X.shape})")
    if X.ndim == 0 or len(X) != V:
        raise InvalidParameterError("X", f"must have one row per input vertex: {V} rows, got "
                                    f"{len(X) if X.ndim else 0} (shape {X.shape})")
    check_finite(X, "X")
    return X


class Stencil(Immutable):
    """The output points of a surface at one resolution as a linear map of the positions.

    Attributes: ``base`` B (P, V), ``mono`` E (P, V M) (csr), ``fits`` the coefficient
    map (:class:`gerbs_core.mesh.coupling.CoupledFits`, c = A X) and ``operator`` A
    (V M, V) (csr, made on first use: a full build needs only ``fits(X)``, partial
    updates need A); ``triangles`` (T, 3), ``vertex_samples`` (V,) the output point of
    each vertex, ``lattice`` (:class:`gerbs_core.mesh.lattice.Lattice`). Immutable; the
    transposes for partial updates are made on first use, and the last moved vertices'
    columns kept (:meth:`moved_columns`).
    """

    def __init__(self, base, mono, fits, lattice):
        self.base, self.mono = _canonical(base), _canonical(mono)
        self.fits = fits
        self.lattice = lattice
        self.vertex_samples = lattice.vertex_sample
        self._csc = None
        self._moved = None  # (key, moved_columns) of the last moved vertices
        self._freeze()

    @property
    def triangles(self) -> np.ndarray:
        """(T, 3) the lattice's output triangles (made on first use)."""
        return self.lattice.triangles

    @property
    def operator(self) -> sp.csr_matrix:
        return self.fits.operator

    @property
    def shape(self) -> tuple[int, int]:
        return self.base.shape

    def __repr__(self) -> str:
        P, V = self.shape
        return (f"Stencil(points={P}, vertices={V}, resolution={self.lattice.resolution}, "
                f"nnz_per_row={self.nnz_per_row():.1f})")

    @property
    def nnz(self) -> int:
        """Stored entries of the three factors."""
        return self.base.nnz + self.mono.nnz + self.operator.nnz

    def apply(self, X) -> np.ndarray:
        """Output points (P, k) (or (P,)) for vertex positions X (V, k) (or (V,)) (the same
        sums for every k: one column at a time). Refused: X with another number of rows
        than the input's vertices (InvalidParameterError ``X``), NaN or infinite entries
        (InvalidMeshError ``non_finite`` naming the rows: the constructor's check, one
        np.isfinite pass: 0.01 % of an apply on
        35k vertices)."""
        X = _positions(X, self.base.shape[1])
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
        coefficient operator (:meth:`CoupledFits.columns`), never the whole operator.

        Refused before ``points`` is touched: ``moved`` outside [0, V) or repeated
        (InvalidParameterError ``moved``), ``delta`` with another row count than ``moved``
        (InvalidParameterError ``delta``), NaN or infinite ``delta`` (InvalidMeshError
        ``non_finite`` naming ``delta``): a bad drag step never corrupts the points."""
        V = self.base.shape[1]
        moved = np.asarray(moved).ravel()
        if moved.dtype.kind not in "iu" or (len(moved) and (moved.min() < 0 or moved.max() >= V)):
            raise InvalidParameterError("moved", f"must be vertex indices in [0, {V}), got "
                                        f"{moved[:8].tolist()}{'...' if len(moved) > 8 else ''}")
        if len(np.unique(moved)) != len(moved):
            raise InvalidParameterError("moved", "must not repeat a vertex")
        try:
            delta = np.asarray(delta, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidParameterError("delta", f"must be a real ({len(moved)}, k) array, got "
                                        f"{type(delta).__name__}") from None
        if delta.ndim not in (1, 2) or len(delta) != len(moved):
            raise InvalidParameterError("delta", f"must have one row per moved vertex: "
                                        f"{len(moved)} rows, got shape {delta.shape}")
        check_finite(delta, "delta")
        P = self.base.shape[0]
        if not isinstance(points, np.ndarray) or points.dtype != np.float64 \
                or points.shape[:1] != (P,) or points.ndim != delta.ndim:
            raise InvalidParameterError("points", f"must be the float64 output points "
                                        f"({P}, k) being updated in place, got "
                                        f"{type(points).__name__} {np.shape(points)}")
        if points.shape[1:] != delta.shape[1:]:
            raise InvalidParameterError("delta", f"must have the points' {points.shape[1:]} "
                                        f"columns per moved vertex, got shape {delta.shape}")
        hit, dW = self.moved_columns(moved)
        if len(hit):
            points[hit] += dW @ delta

    def moved_columns(self, moved) -> tuple[np.ndarray, sp.csr_matrix]:
        """(hit (h,) the output rows the vertices ``moved`` (m,) reach, dW (h, m) csr:
        those rows of W's columns ``moved``, as B[:, moved] + E[:, rows] C[rows] with C
        the coefficient map's columns ``moved`` and rows those C reaches). Memoized for
        the last ``moved`` (a drag moves the same vertices step after step: each step is
        then one small product)."""
        moved = np.asarray(moved, dtype=np.int64).ravel()
        key = moved.tobytes()
        if self._moved is not None and self._moved[0] == key:
            return self._moved[1]
        if self._csc is None:
            self._cache("_csc", (self.base.tocsc(), self.mono.tocsc()))
        Bc, Ec = self._csc
        # coefficient changes on the rows the moved columns touch only (csc C: its row
        # indices; never an O(V M) pass over all coefficient rows)
        C = self.fits.columns(moved).tocoo()
        rows = np.unique(C.row)
        Cr = sp.csr_matrix((C.data, (np.searchsorted(rows, C.row), C.col)),
                           shape=(len(rows), len(moved)))
        cols = (Bc[:, moved] + Ec[:, rows] @ Cr).tocsr()
        hit = np.flatnonzero(np.diff(cols.indptr))
        plan = (hit, _canonical(cols[hit]))
        self._cache("_moved", (key, plan))
        return plan

    def matrix(self) -> sp.csr_matrix:
        """The explicit W = B + E A (P, V) -- for tests and small meshes; it holds many
        more entries than the factors."""
        return (self.base + self.mono @ self.operator).tocsr()

    def nnz_per_row(self) -> float:
        return self.nnz / max(self.base.shape[0], 1)
