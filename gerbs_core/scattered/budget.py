"""Working-memory accounting of the scattered interpolator's evaluation.

Evaluation runs over query chunks whose rows are sized from the candidate count K
of each block, so the working arrays of one chunk stay within ``work_bytes``;
the memory a call needs is then the output plus the inputs' reordering plus one
chunk, which :func:`call_estimate` states before anything is allocated.
The byte counts below are upper bounds calibrated with tracemalloc (see
tests/core/test_scattered_memory.py), not exact.
"""
from __future__ import annotations

import numpy as np

from ..errors import ResourceLimitError

__all__ = ["row_bytes", "rows_per_step", "call_estimate", "byte_size", "check_budget",
           "spatial_order"]

# query rows per evaluation step at most: its ~40 temporaries of (rows, K) then stay below
# glibc's mmap threshold (no page faults of fresh mappings) and in cache
CACHE_ROWS = 4096


def row_bytes(K, n, V, nu, coefs, pairs=0):
    """Bytes of working arrays per query row with K candidates (upper bound).

    ``coefs``: Taylor coefficients per point and value gathered per candidate;
    ``pairs``: (star, corner) pairs per row of the n-D star gauge (0 otherwise).
    """
    jet = 1 + (n if nu >= 1 else 0) + (n * n if nu >= 2 else 0)
    taylor = V * coefs
    per_cand = 8 * (4 * n + 10 * jet + 3 * taylor + 3 * V * jet) + 32
    per_pair = 8 * ((n + 1) * n + 3 * (n + 1) + 8)
    return int(K * per_cand + pairs * per_pair + 8 * V * jet * 2 + 64)


def rows_per_step(work_bytes, row_bytes_):
    """Query rows per evaluation step: what the working memory holds, at most CACHE_ROWS
    (rows are computed independently: the split does not change the bits)."""
    return int(max(1, min(work_bytes // row_bytes_, CACHE_ROWS)))


def call_estimate(M, n, V, nu, work_bytes):
    """Bytes an evaluation of M queries needs at peak: output + ordering + one chunk."""
    out = 8 * M * V * n ** nu
    inputs = 8 * M * (n + 2)
    return int(out + inputs + work_bytes)


def byte_size(b) -> str:
    """A byte count for messages, 3 significant digits in the largest fitting unit
    (GB, MB, kB, bytes): a budget of 1e4 bytes reads "10 kB", not "0 MB"."""
    b = float(b)
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if b >= size:
            return f"{b / size:.3g} {unit}"
    return f"{b:.0f} bytes"


def check_budget(M, n, V, nu, work_bytes, budget):
    """Raise ResourceLimitError (naming ``memory_budget``) before allocating."""
    est = call_estimate(M, n, V, nu, work_bytes)
    if est > budget:
        raise ResourceLimitError(
            f"{M} queries with nu={nu}: estimated memory {byte_size(est)} exceeds the "
            f"budget {byte_size(budget)} (memory_budget); evaluate fewer points per call")
    return est


def spatial_order(x, cells_per_axis):
    """A permutation visiting x (M, n) along a Morton (Z-order) curve of a grid with
    ``cells_per_axis`` cells per axis: point location walks and neighbour gathers
    then stay local for unordered queries."""
    M, n = x.shape
    bits = max(1, min(int(np.ceil(np.log2(max(cells_per_axis, 2)))), 62 // n))
    # per column: an axis-0 reduction of an (M, n) array is 5x slower (same values)
    lo = np.array([x[:, a].min() for a in range(n)])
    hi = np.array([x[:, a].max() for a in range(n)])
    q = ((x - lo) / np.maximum(hi - lo, 1e-300) * ((1 << bits) - 1)).astype(np.int64)
    # bit b of coordinate a goes to bit n b + n - 1 - a: spread 8 bits at a time by table
    spread = np.zeros(256, np.int64)
    for i in range(8):
        spread |= ((np.arange(256) >> i) & 1) << (i * n)
    code = np.zeros(M, np.int64)
    for a in range(n):
        for k in range(0, bits, 8):
            keep = (1 << min(8, bits - k)) - 1          # (only the low ``bits`` bits)
            code |= spread[(q[:, a] >> k) & keep] << (k * n + n - 1 - a)
    # the smallest unsigned type holding the codes: a stable sort of the same keys is the
    # same permutation, and numpy radix-sorts 16-bit keys (15x faster than int64)
    nb = bits * n
    return np.argsort(code.astype(np.uint16 if nb <= 16 else np.uint32 if nb <= 32 else np.int64),
                      kind="stable")
