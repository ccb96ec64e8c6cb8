"""The fast path of a sync: new output points from moved vertices with the cached stencil.

In both face-shape modes every output point is a fixed linear combination of
the vertex positions, ``P = W @ X`` (DESIGN section 5), so an edit that keeps
the topology and the settings needs only this product -- or, when a few
vertices moved (a drag), only their columns of W.
"""
from __future__ import annotations

import numpy as np

_PARTIAL_MAX_SHARE = 0.05  # partial update when the moved columns hold <= 5% of W's entries
_PARTIAL_REFRESH = 256  # full W @ X after this many partial updates (bounds round-off drift)
_SCAN_MAX_MOVED = 4  # up to this many moved vertices: find their entries by scanning W's
# column indices (0.45 ms per vertex on Suzanne r=16) instead of building the csc
# transpose (8-11 ms, which made the first drag step after a rebuild slow)


def apply_stencil(st, X: np.ndarray) -> np.ndarray:
    """Output points (P, 3) for new positions X (V, 3) of the state `st` (an
    engine.SurfaceState, updated in place): W @ X, or, when few vertices moved (an Edit
    Mode drag), P += W[:, moved] (X - X_old)[moved], touching only the samples in the
    moved vertices' supports (the same sum, regrouped; refreshed every
    ``_PARTIAL_REFRESH`` updates so round-off cannot accumulate). The moved columns'
    entries come from a scan of W's column indices for up to ``_SCAN_MAX_MOVED``
    vertices, else from the csc transpose (made once, on first need)."""
    moved = np.flatnonzero(np.any(X != st.positions, axis=1))
    if (st.points is not None and st.partial_updates < _PARTIAL_REFRESH
            and st.matrix_csc is None and 0 < len(moved) <= _SCAN_MAX_MOVED):
        W = st.matrix
        hit = W.indices == moved[0]
        for w in moved[1:]:
            hit |= W.indices == w
        pos = np.flatnonzero(hit)  # the entries of the moved columns, in row order
        if len(pos) <= _PARTIAL_MAX_SHARE * W.nnz:
            rows = np.searchsorted(W.indptr, pos, side="right") - 1
            delta = (X - st.positions)[W.indices[pos]]
            np.add.at(st.points, rows, W.data[pos, None] * delta)
            st.partial_updates += 1
            return st.points
    if st.points is not None and st.partial_updates < _PARTIAL_REFRESH:
        if st.matrix_csc is None:
            st.matrix_csc = st.matrix.tocsc()
        ptr = st.matrix_csc.indptr
        counts = ptr[moved + 1] - ptr[moved]
        total = int(counts.sum())
        if total <= _PARTIAL_MAX_SHARE * st.matrix_csc.nnz:
            # entry indices of the moved columns, concatenated
            idx = np.repeat(ptr[moved] - np.cumsum(counts) + counts, counts) + np.arange(total)
            delta = (X - st.positions)[np.repeat(moved, counts)]
            np.add.at(st.points, st.matrix_csc.indices[idx], st.matrix_csc.data[idx, None] * delta)
            st.partial_updates += 1
            return st.points
    st.points = product(st.matrix, X, st.points)
    st.partial_updates = 0
    return st.points


def product(W, X: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """W @ X as three sparse mat-vecs (measured 1.5x faster than scipy's csr @ (V, 3))."""
    XT = np.ascontiguousarray(X.T)
    if out is None or out.shape != (W.shape[0], 3):
        out = np.empty((W.shape[0], 3))
    for k in range(3):
        out[:, k] = W @ XT[k]
    return out


