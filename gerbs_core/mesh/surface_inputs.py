"""Input checks of :class:`~gerbs_core.mesh.surface.BlendingSurface`: positions, settings
and face points, each refused with an :class:`~gerbs_core.errors.InvalidParameterError`
naming the parameter. Arrays are copied, so the caller's are never aliased or modified.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from .agreement import FairnessRule
from .charts import BOUNDARY_RULES
from .repair import _warning as mesh_warning

__all__ = ["points", "positive", "unit_normals", "check_settings", "face_points"]


def points(name, a, V=None) -> np.ndarray:
    """A float64 copy of the (V, 3) array `a` (any V if None)."""
    try:
        x = np.array(a, dtype=np.float64, copy=True)  # never alias the caller's array
    except (TypeError, ValueError):
        raise InvalidParameterError(name, f"must be a real (V, 3) array, got {type(a).__name__}") \
            from None
    if x.ndim != 2 or x.shape[1] != 3 or (V is not None and len(x) != V):
        raise InvalidParameterError(name, f"must be a ({'V' if V is None else V}, 3) array, "
                                    f"got shape {x.shape}")
    return x


def positive(name, value, integer=False, lo=0.0, closed=False):
    """`value` as a finite float (or int with `integer`) > lo (>= lo with `closed`)."""
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if ok:
        v = float(value)
        ok = np.isfinite(v) and (v >= lo if closed else v > lo) and (not integer or v == int(v))
    if not ok:
        kind = "an integer" if integer else "a finite number"
        raise InvalidParameterError(name, f"must be {kind} {'>=' if closed else '>'} {lo:g}, "
                                    f"got {value!r}")
    return int(value) if integer else float(value)


def unit_normals(normals, V: int, keep):
    """Unit vectors along `normals` (V, 3) at the vertices ``keep`` (K,): ((K, 3), warning).

    Only the kept vertices' normals must be finite: the repair drops degenerate faces, and
    a vertex only they used may carry anything. A zero normal at a kept vertex means "no
    normal there": its row is zero (the Hermite projection then leaves that vertex's
    tangent plane to the fit) and ``warning`` (a repair-style MeshWarning naming the input
    vertices, tag ``zero_normal``) says so, else None. (At the one case measured, the lone
    middle vertex of a collinear triangle, Blender gives a unit normal: zero rows come
    from scripts' data.)"""
    idx = np.asarray(keep)
    nrm = points("normals", normals, V)[idx]
    ln = np.linalg.norm(nrm, axis=1)
    bad = ~np.isfinite(ln)
    if bad.any():
        raise InvalidParameterError("normals", f"must be finite (vertex indices "
                                    f"{idx[bad][:10].tolist()})")
    zero = ln == 0
    out = np.divide(nrm, ln[:, None], out=np.zeros_like(nrm), where=~zero[:, None])
    if not zero.any():
        return out, None
    return out, mesh_warning("zero_normal", idx[zero], "vertex")


def check_settings(boundary, kappa, shrink, fairness) -> FairnessRule:
    """Check the boundary rule and the cover's envelope parameters; return the fairness
    rule (default :class:`FairnessRule`)."""
    if boundary not in BOUNDARY_RULES:
        raise InvalidParameterError("boundary", f"must be one of {BOUNDARY_RULES}, got "
                                    f"{boundary!r}")
    if not (isinstance(shrink, (int, float)) and 0.0 < shrink <= 1.0):
        raise InvalidParameterError("shrink", f"must be in (0, 1], got {shrink!r}")
    if not (isinstance(kappa, (int, float)) and 0.0 < kappa < 1.0):
        raise InvalidParameterError("kappa", f"must be in (0, 1), got {kappa!r}")
    fairness = FairnessRule() if fairness is None else fairness
    if not isinstance(fairness, FairnessRule):
        raise InvalidParameterError("fairness", "must be a FairnessRule")
    return fairness


def face_points(face_index, local_coords, n_faces: int):
    """(faces (N,), points (N, 2), shape) of face indices broadcast against layout
    coordinates (..., 2): finite coordinates, integer faces in [0, n_faces)."""
    x = np.asarray(local_coords, dtype=np.float64)
    if x.shape[-1:] != (2,):
        raise InvalidParameterError("local_coords", f"must have shape (..., 2), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InvalidParameterError("local_coords", "must be finite")
    try:
        f = np.broadcast_to(np.asarray(face_index), x.shape[:-1])
    except ValueError:
        raise InvalidParameterError("face_index", f"does not broadcast against "
                                    f"local_coords {x.shape}") from None
    if f.dtype.kind not in "iu":
        raise InvalidParameterError("face_index", "must be integers")
    f = f.astype(np.int64).ravel()
    if np.any((f < 0) | (f >= n_faces)):
        raise InvalidParameterError("face_index", "out of range")
    return f, x.reshape(-1, 2), x.shape[:-1]
