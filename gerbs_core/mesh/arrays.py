"""Read-only arrays: the immutable objects of :mod:`gerbs_core.mesh` (topologies,
lattices) hand out their arrays frozen, so no caller can change them behind a cache."""
from __future__ import annotations

import numpy as np

__all__ = ["read_only", "ranges", "unique_rows"]


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


def unique_rows(a) -> tuple[np.ndarray, np.ndarray]:
    """(first (U,), inverse (N,)) of the distinct rows of a (N, k): as
    ``np.unique(a, axis=0, return_index=True, return_inverse=True)[1:]`` -- the groups
    numbered in lexicographic (numeric) order of their rows, first[u] the lowest row of
    group u -- by one stable lexsort of the columns (np.unique sorts the rows as
    structured records: ~7x slower on 65k rows of 7 floats)."""
    a = np.asarray(a)
    if len(a) == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    a = a.reshape(len(a), -1)
    order = np.lexsort(a.T[::-1])
    s = a[order]
    new = np.empty(len(a), dtype=bool)
    new[0] = True
    np.any(s[1:] != s[:-1], axis=1, out=new[1:])
    inverse = np.empty(len(a), dtype=np.intp)
    inverse[order] = np.cumsum(new) - 1
    return order[new], inverse
