"""Input checks of :class:`~gerbs_core.mesh.surface.BlendingSurface`: positions, settings
and face points, each refused with an :class:`~gerbs_core.errors.InvalidParameterError`
naming the parameter. Arrays are copied, so the caller's are never aliased or modified.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from ..inputs import real_array
from .agreement import FairnessRule
from .charts import BOUNDARY_RULES
from .repair import _warning as mesh_warning

__all__ = ["points", "positive", "unit_normals", "check_settings", "face_points", "inside_faces",
           "chart_points"]


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


# a face point may lie this far outside its layout polygon, relative to the face's longest
# edge (points on an edge or at a corner computed in floating point land within it)
OUTSIDE_TOL = 1e-9


def face_points(face_index, local_coords, n_faces: int, polygons=None):
    """(faces (N,), points (N, 2), shape) of face indices broadcast against layout
    coordinates (..., 2): finite coordinates, integer faces in [0, n_faces); with
    ``polygons`` = (layout corners (C, 2), face offsets (F + 1,)) also every point inside
    (or within ``OUTSIDE_TOL`` of) its face's layout polygon, which is convex and
    counter-clockwise (:mod:`gerbs_core.mesh.layout`): outside it the surface is not
    defined (the cover's functions extrapolate, or leave the point uncovered)."""
    x = real_array("local_coords", local_coords, copy=False)
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
        raise InvalidParameterError("face_index", f"must lie in [0, {n_faces}), got "
                                    f"{f[(f < 0) | (f >= n_faces)][:5].tolist()}")
    x2 = x.reshape(-1, 2)
    if polygons is not None and len(f):
        out = np.flatnonzero(~inside_faces(f, x2, *polygons))
        if len(out):
            raise InvalidParameterError(
                "local_coords", f"{len(out)} point(s) lie outside their faces (first indices "
                f"{out[:5].tolist()}, e.g. {x2[out[0]].tolist()} in face {int(f[out[0]])}): "
                f"points are given in the face's own layout polygon (gerbs_core.mesh.layout; "
                f"BlendingSurface.layouts.corners), where the surface is defined")
    return f, x2, x.shape[:-1]


def inside_faces(f, x, corners, offsets):
    """(N,) bool: point x[i] (N, 2) lies in face f[i]'s convex counter-clockwise layout
    polygon, or within OUTSIDE_TOL of its longest edge outside it. Points grouped by their
    face's size: each pays for its own face's edges only (a 200-gon's points 200 steps,
    the others' 3 or 4)."""
    offsets = np.asarray(offsets)
    f = np.asarray(f)
    size = offsets[f + 1] - offsets[f]
    ok = np.ones(len(f), bool)
    for n in np.unique(size).tolist():
        at = np.flatnonzero(size == n)
        first, p = offsets[f[at]], x[at]
        worst, longest = np.full(len(at), np.inf), np.zeros(len(at))
        for k in range(n):
            a, b = first + k, first + (k + 1) % n
            e = corners[b] - corners[a]
            ln = np.hypot(e[:, 0], e[:, 1])
            d = p - corners[a]
            dist = (e[:, 0] * d[:, 1] - e[:, 1] * d[:, 0]) / np.maximum(ln, 1e-300)  # left: +
            np.minimum(worst, dist, out=worst)
            np.maximum(longest, ln, out=longest)
        ok[at] = worst >= -OUTSIDE_TOL * longest
    return ok



def chart_points(y) -> np.ndarray:
    """(N, 2) float64 chart points from `y` (2,) or (N, 2), finite."""
    y = np.atleast_2d(real_array("y", y, copy=False))
    if y.ndim != 2 or y.shape[1] != 2:
        raise InvalidParameterError("y", f"must be chart points of shape (N, 2) or (2,), got "
                                    f"shape {np.shape(y)}")
    if not np.all(np.isfinite(y)):
        raise InvalidParameterError("y", "must be finite")
    return y
