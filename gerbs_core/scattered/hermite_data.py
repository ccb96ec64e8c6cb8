"""The Hermite data of :class:`~gerbs_core.scattered.hermite.GERBSInterpolator`: the
user's values, gradients and Hessians checked and flattened to the derivative tensors
D = [D0 (N, V), D1 (N, V, n), D2 (N, V, n, n)] of :mod:`.taylor`."""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError, InvalidPointSetError
from ..inputs import real_array

__all__ = ["hermite_data"]


def hermite_data(values, gradients, hessians, N, n):
    """(D, vshape, V): the data as tensors with the value shape vshape flattened to V.

    values (N, *vshape); gradients (N, *vshape, n) and Hessians (N, *vshape, n, n)
    optional (Hessians only with gradients; symmetrised). Copies; raises
    InvalidParameterError for wrong shapes and InvalidPointSetError naming the points
    with non-finite data.
    """
    vals = real_array("values", values)
    if vals.ndim == 0 or vals.shape[0] != N:
        raise InvalidParameterError("values", f"expected shape (N={N}, ...), got {np.shape(values)}")
    vshape = vals.shape[1:]
    V = int(np.prod(vshape)) if vshape else 1
    bad = np.flatnonzero(~np.all(np.isfinite(vals.reshape(N, -1)), axis=1))
    if bad.size:
        raise InvalidPointSetError("values: non-finite (NaN or inf) at indices", bad)
    D = [vals.reshape(N, V)]
    if hessians is not None and gradients is None:
        raise InvalidParameterError("hessians", "Hessians need gradients too")
    for name, arr, k in (("gradients", gradients, 1), ("hessians", hessians, 2)):
        if arr is None:
            break
        a = real_array(name, arr)
        want = (N,) + vshape + (n,) * k
        if a.shape != want:
            raise InvalidParameterError(name, f"expected shape {want}, got {a.shape}")
        bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(N, -1)), axis=1))
        if bad.size:
            raise InvalidPointSetError(f"{name}: non-finite (NaN or inf) at indices", bad)
        a = a.reshape((N, V) + (n,) * k)
        if k == 2:
            a = 0.5 * (a + np.swapaxes(a, -1, -2))
        D.append(a)
    return D, vshape, V
