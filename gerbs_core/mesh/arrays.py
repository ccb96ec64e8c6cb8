"""Read-only arrays: the immutable objects of :mod:`gerbs_core.mesh` (topologies,
lattices) hand out their arrays frozen, so no caller can change them behind a cache."""
from __future__ import annotations

import numpy as np

__all__ = ["read_only", "ranges"]


def read_only(a) -> np.ndarray:
    """`a` as a C-contiguous array (a copy only if needed) with writing disabled."""
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


def ranges(starts, counts) -> np.ndarray:
    """Concatenated aranges [starts[i], starts[i] + counts[i]) (int64): the positions of
    ragged runs, e.g. every entry of the CSR rows ``starts = indptr[rows]``."""
    counts = np.asarray(counts, dtype=np.int64)
    first = np.cumsum(counts) - counts
    return np.repeat(np.asarray(starts, dtype=np.int64) - first, counts) + np.arange(int(counts.sum()))
