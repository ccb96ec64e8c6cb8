"""The default ERBS's tables, stored with the package.

Building them (:func:`~.erbs_table.build_tables`: adaptive quadrature, the value
table's search, the clip interval) costs ~14 ms of CPU, most of a small first call of
anything that uses ``ERBS()`` (a 4,000-point scattered interpolant is ~100 ms); loading
them from ``erbs_default.npy`` costs ~0.1 ms. The file holds the build's arrays bit for
bit (tests/core/test_kernels_erbs.py rebuilds and compares; regenerate with
``erbs_store.regenerate()``); when it is missing, unreadable or of
another layout, the tables are built as for every other parameter set.

Layout: one flat float64 array, a header of ``_HEAD`` numbers (layout version, the
sizes, Z, the master's tail sum, the log scale, the clip interval or NaN), then the
master's a, b, integrated coefficients, left sums and breaks, then the value table's
breaks and coefficients. (One .npy: an .npz costs 6 ms of zipfile on first use.)
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ._table import ChebyshevMaster, PiecewisePoly

__all__ = ["DEFAULT", "PATH", "load", "save", "pack", "unpack", "regenerate"]

DEFAULT = (1.0, 1.0, 1.0, 0.5, 1.0)     # ERBS() : (alpha, beta, gamma, lam, sigma)
PATH = Path(__file__).with_name("erbs_default.npy")
_VERSION = 1.0
_HEAD = 12


def pack(tables) -> np.ndarray:
    """(master, table, clip, shift) -> the flat array of the module docstring."""
    master, table, clip, shift = tables
    coef = np.array(table.coef)
    lo, hi = (np.nan, np.nan) if clip is None else clip
    head = [_VERSION, master.a.size, master.icoef.shape[1], table.breaks.size, coef.shape[0],
            float(table.uniform), master.Z, master.tail_sum, shift, lo, hi, 0.0]
    return np.concatenate([np.array(head, float), master.a, master.b, master.icoef.ravel(),
                           master.left, master.breaks, table.breaks, coef.ravel()])


def unpack(flat: np.ndarray):
    """The flat array -> (master, table, clip, shift); ValueError if the layout differs."""
    if flat.ndim != 1 or flat.size < _HEAD or flat[0] != _VERSION:
        raise ValueError("not a stored ERBS table of this layout")
    n, k, m, d = (int(v) for v in flat[1:5])
    sizes = [n, n, n * k, n, n + 1, m, d * m]
    if flat.size != _HEAD + sum(sizes):
        raise ValueError("stored ERBS table: sizes do not match")
    a, b, icoef, left, breaks, tbreaks, coef = np.split(flat[_HEAD:], np.cumsum(sizes)[:-1])
    master = ChebyshevMaster.from_arrays(a.copy(), b.copy(), icoef.reshape(n, k).copy(),
                                         float(flat[6]), left.copy(), breaks.copy(),
                                         float(flat[7]))
    table = PiecewisePoly(tbreaks.copy(), coef.reshape(d, m), uniform=bool(flat[5]))
    clip = None if np.isnan(flat[9]) else (float(flat[9]), float(flat[10]))
    return master, table, clip, float(flat[8])


def load(path=PATH):
    """The stored default tables, or None (missing, unreadable or another layout)."""
    try:
        return unpack(np.load(path, allow_pickle=False))
    except (OSError, ValueError):
        return None


def save(tables, path=PATH) -> None:
    np.save(path, pack(tables), allow_pickle=False)


def regenerate(path=PATH) -> None:
    """Rebuild the default tables (not from the store) and write them to ``path``.

    Run with OPENBLAS_NUM_THREADS=1: the build's Vandermonde inverse (LAPACK) rounds
    differently with threaded BLAS, and the adaptive quadrature then settles on other
    cells (82 single-threaded, 79 with 2 threads; both meet the 5e-15 table tolerance).
    The stored file makes ERBS() the same everywhere."""
    import os
    if os.environ.get("OPENBLAS_NUM_THREADS") != "1":
        raise RuntimeError("regenerate the stored ERBS tables with OPENBLAS_NUM_THREADS=1")
    from .erbs import ERBS
    from .erbs_table import build_tables
    save(build_tables.__wrapped__(ERBS, DEFAULT), path)
