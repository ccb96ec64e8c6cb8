"""The fast path of a sync: new output points from moved vertices with the cached stencil.

Every output point is a fixed linear combination of the vertex positions for the
rest shape bound at build time (:class:`gerbs_core.mesh.stencil.Stencil`), so an
edit that keeps the topology and the settings needs only the stencil applied --
or, when a few vertices moved (an Edit Mode drag), only their contribution.
"""
from __future__ import annotations

import numpy as np

_PARTIAL_MAX_SHARE = 0.05  # partial update while at most 5% of the vertices moved
_PARTIAL_REFRESH = 256  # full product after this many partial updates (bounds round-off drift)


def moved_vertices(new: np.ndarray, old: np.ndarray) -> np.ndarray:
    """(m,) sorted rows where the positions `new` and `old` (V, 3) differ (NaN differs):
    one pass over the flat arrays (``np.any(..., axis=1)`` costs ~10x more)."""
    return np.unique(np.flatnonzero(np.ravel(new) != np.ravel(old)) // 3)


def apply_stencil(st, X: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(output points (P, 3) float32 as Blender stores them, the moved vertices (m,) or
    None for a full product) for new positions X (V, 3) float64 of the state `st` (an
    engine.SurfaceState, updated in place): the full product, or, when few vertices
    moved, ``points += the moved vertices' contribution`` (the same sums, regrouped;
    refreshed every ``_PARTIAL_REFRESH`` updates so round-off cannot accumulate) and
    only the rows it reaches converted to float32. ``(None, None)`` when a point is not
    finite as float32 (a surface beyond its range): nothing may be written then, and `st`
    is spent (the caller rebuilds, which reports why)."""
    moved = moved_vertices(X, st.positions)
    with np.errstate(over="ignore", invalid="ignore"):
        if (st.points is not None and st.points32 is not None
                and st.partial_updates < _PARTIAL_REFRESH
                and 0 < len(moved) <= _PARTIAL_MAX_SHARE * len(X)):
            hit, _ = st.stencil.moved_columns(moved)
            st.stencil.apply_moved(st.points, moved, X[moved] - st.positions[moved])
            st.points32[hit] = st.points[hit]
            st.partial_updates += 1
            if not np.all(np.isfinite(st.points32[hit])):
                return None, None
            return st.points32, moved
        st.points = st.stencil.apply(X)
        st.points32 = st.points.astype(np.float32)
    st.partial_updates = 0
    if not np.all(np.isfinite(st.points32)):
        return None, None
    return st.points32, None
