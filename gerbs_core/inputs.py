"""The package's checks of plain arguments, each refusing with an
:class:`~gerbs_core.errors.InvalidParameterError` that names the argument (as scipy's
errors do): real arrays, indices, radii. Domain-specific checks (meshes, point sets)
live beside their objects and use these.
"""
from __future__ import annotations

import numpy as np

from .errors import InvalidParameterError

__all__ = ["real_array", "is_integer", "integer", "check_index", "radii"]


def real_array(name: str, a, copy: bool = True) -> np.ndarray:
    """`a` as a float64 array (a copy unless `copy` is False and it is one already):
    numbers only (bool, int, float); strings, complex numbers and objects are refused."""
    try:
        x = np.array(a, copy=copy) if copy else np.asarray(a)
    except (TypeError, ValueError):
        raise InvalidParameterError(name, f"must be an array of real numbers, got "
                                    f"{type(a).__name__}") from None
    if x.dtype.kind not in "biuf":
        raise InvalidParameterError(name, f"must be real numbers, got an array of dtype "
                                    f"{x.dtype}")
    return x.astype(np.float64, copy=False)


def is_integer(value) -> bool:
    """An int, Python or numpy, and not a bool (a float, even 1.0, is not)."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def integer(name: str, value, lo: int = 0, what: str = "") -> int:
    """`value` as an int >= lo (:func:`is_integer`); `what` follows the bound in the message,
    e.g. " (segments per edge)"."""
    if not is_integer(value) or value < lo:
        raise InvalidParameterError(name, f"must be an integer >= {lo}{what}, got {value!r}")
    return int(value)


def check_index(name: str, i, n: int) -> int:
    """`i` as an index in [0, n): an int (:func:`is_integer`), no negative wrap-around."""
    if not is_integer(i) or not 0 <= int(i) < n:
        raise InvalidParameterError(name, f"must be an index in [0, {n}), got {i!r}")
    return int(i)


def radii(name: str, r, N: int) -> np.ndarray:
    """(N,) float64 radii from a scalar or an (N,) array: finite and > 0."""
    x = real_array(name, r)
    if x.ndim > 1 or (x.ndim == 1 and len(x) != N):
        raise InvalidParameterError(name, f"must be a number or an array of shape ({N},), "
                                    f"got shape {x.shape}")
    x = np.broadcast_to(x, (N,)).copy()
    bad = np.flatnonzero(~(np.isfinite(x) & (x > 0)))
    if len(bad):
        raise InvalidParameterError(name, f"must be finite and > 0 (indices "
                                    f"{bad[:10].tolist()}, values {x[bad[:3]].tolist()})")
    return x
