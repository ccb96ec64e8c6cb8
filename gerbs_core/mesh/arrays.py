"""Read-only arrays: the immutable objects of :mod:`gerbs_core.mesh` (topologies,
lattices) hand out their arrays frozen, so no caller can change them behind a cache."""
from __future__ import annotations

import numpy as np

__all__ = ["read_only"]


def read_only(a) -> np.ndarray:
    """`a` as a C-contiguous array (a copy only if needed) with writing disabled."""
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a
