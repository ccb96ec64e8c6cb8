"""The selection of rows of a vertex array as a sparse matrix: X[source] = S X.

Composing a map of selected positions with S makes it a map of all positions; S has
a single 1 per row, so products with it only move (and, for repeated sources, add)
columns. Serves the repaired mesh's vertices (:mod:`.repair`) and the coefficient
maps of selected positions (:class:`~gerbs_core.mesh.coupling.SelectedFits`) and the
crease cut's copies (:class:`~gerbs_core.mesh.creases.CreaseCut`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["selection_matrix"]


def selection_matrix(source, n_source: int) -> sp.csr_matrix:
    """(n, n_source) csr with S[i, source[i]] = 1 (float64), so that S @ X == X[source]
    for X (n_source, k); ``source`` (n,) int indices in [0, n_source)."""
    n = len(source)
    return sp.csr_matrix((np.ones(n), (np.arange(n), source)), shape=(n, n_source))
