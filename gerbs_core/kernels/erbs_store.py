"""The default ERBS's tables, stored with the package.

Building them (:func:`~.erbs_table.build_tables`: adaptive quadrature, the value
table's search, the clip interval) costs ~14 ms of CPU, most of a small first call of
anything that uses ``ERBS()`` (a 4,000-point scattered interpolant is ~100 ms); loading
them from ``erbs_default.npy`` costs ~0.1 ms. The file holds the build's arrays bit for
bit as made on one machine (regenerate with ``erbs_store.regenerate()``); another
processor's BLAS rounds the build differently and its quadrature may settle on other cells
(118 against 82 on a new machine), so tests/core/test_kernels_erbs.py compares the kernel
the file gives with a rebuild's to 1e-14 of each derivative's scale, and the file makes
ERBS() the same everywhere. When it is missing, unreadable or of
another layout, the tables are built as for every other parameter set.

Layout: one flat float64 array, a header of ``_HEAD`` numbers (layout version, the
sizes, Z, the master's tail sum, the log scale, the clip interval or NaN), then the
master's a, b, integrated coefficients, left sums and breaks, then the value table's
breaks and coefficients. (One .npy: an .npz costs 6 ms of zipfile on first use.)
"""
from __future__ import annotations

import zlib
from functools import lru_cache
from pathlib import Path

import numpy as np

from ._table import ChebyshevMaster, PiecewisePoly

__all__ = ["DEFAULT", "PATH", "load", "save", "pack", "unpack", "regenerate"]

DEFAULT = (1.0, 1.0, 1.0, 0.5, 1.0)     # ERBS() : (alpha, beta, gamma, lam, sigma)
PATH = Path(__file__).with_name("erbs_default.npy")
_VERSION = 2.0
_HEAD = 17
_BUILDER = ("erbs.py", "erbs_table.py", "_table.py", "_series.py")   # what the build runs


@lru_cache(maxsize=1)
def fingerprint() -> float:
    """CRC-32 of the builder's source files (:data:`_BUILDER`), as a float (exact)."""
    here = Path(__file__).parent
    crc = 0
    for name in _BUILDER:
        crc = zlib.crc32((here / name).read_bytes(), crc)
    return float(crc)


def pack(tables, params=DEFAULT) -> np.ndarray:
    """(master, table, clip, shift) built for ``params`` (alpha, beta, gamma, lam, sigma)
    -> the flat array of the module docstring."""
    master, table, clip, shift = tables
    coef = np.array(table.coef)
    lo, hi = (np.nan, np.nan) if clip is None else clip
    head = [_VERSION, master.a.size, master.icoef.shape[1], table.breaks.size, coef.shape[0],
            float(table.uniform), master.Z, master.tail_sum, shift, lo, hi, fingerprint(),
            *(float(p) for p in params)]
    return np.concatenate([np.array(head, float), master.a, master.b, master.icoef.ravel(),
                           master.left, master.breaks, table.breaks, coef.ravel()])


def unpack(flat: np.ndarray):
    """The flat array -> (master, table, clip, shift); ValueError if the layout, the
    parameters or the builder's fingerprint differ."""
    if flat.dtype != np.float64 or flat.ndim != 1 or flat.size < _HEAD or flat[0] != _VERSION:
        raise ValueError("not a stored ERBS table of this layout")
    if flat[11] != fingerprint() or tuple(flat[12:_HEAD]) != DEFAULT:
        raise ValueError("stored ERBS table: made for other parameters or by other code")
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
    """The stored default tables, or None (missing, unreadable, empty, another layout,
    other parameters or another builder)."""
    try:
        return unpack(np.load(path, allow_pickle=False))
    except (OSError, ValueError, EOFError):
        return None


def save(tables, params=DEFAULT, path=PATH) -> None:
    """Write ``tables`` built for ``params`` (only the default's are ever loaded)."""
    np.save(path, pack(tables, params), allow_pickle=False)


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
    save(build_tables.__wrapped__(ERBS, DEFAULT), DEFAULT, path)
