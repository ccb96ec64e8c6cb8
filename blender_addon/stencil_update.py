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


def apply_stencil(st, X: np.ndarray) -> np.ndarray:
    """Output points (P, 3) for new positions X (V, 3) of the state `st` (an
    engine.SurfaceState, updated in place): the full product, or, when few vertices
    moved, ``points += the moved vertices' contribution`` (the same sums, regrouped;
    refreshed every ``_PARTIAL_REFRESH`` updates so round-off cannot accumulate)."""
    moved = np.flatnonzero(np.any(X != st.positions, axis=1))
    if (st.points is not None and st.partial_updates < _PARTIAL_REFRESH
            and 0 < len(moved) <= _PARTIAL_MAX_SHARE * len(X)):
        st.stencil.apply_moved(st.points, moved, (X - st.positions)[moved])
        st.partial_updates += 1
        return st.points
    st.points = st.stencil.apply(X)
    st.partial_updates = 0
    return st.points
