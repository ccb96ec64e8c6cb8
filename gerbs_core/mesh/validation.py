"""Checks of vertex positions against a mesh topology (before any surface is built).

Problem tags, checked in this order (the first failing check raises an
:class:`~gerbs_core.errors.InvalidMeshError` naming all its offending elements):

``bad_shape``        wrong shape, count or dtype (element vertex)
``non_finite``       NaN or infinite coordinates (element vertex)
``outlier_vertex``   vertices whose edges are all more than ``OUTLIER_FACTOR`` times
                     the mesh's median edge length: a stray coordinate (1e20 in one
                     vertex) would otherwise make every other edge look of zero length
``zero_length_edge`` an edge no longer than ``rtol`` times the median edge length
``degenerate_face``  zero-area (collinear or self-cancelling) faces
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidMeshError, InvalidParameterError
from .topology import MeshTopology
from .topology_build import edge_error

__all__ = ["validate_geometry", "flat_faces", "chain_faces", "not_a_polygon", "face_vector_areas",
           "corner_successors",
           "check_finite", "check_outliers", "OUTLIER_FACTOR"]

# A vertex whose shortest edge is 1e6 median edge lengths away is a stray coordinate,
# not a feature: at that scale ratio float64 keeps only ~10 digits of the rest of the
# mesh in any expression that mixes both.
OUTLIER_FACTOR = 1e6

# The margin by which a face's longest edge must be shorter than the sum of its others for
# the face to have a convex layout polygon (layout.face_layouts, repair's zero-area faces).
CHAIN_RTOL = 1e-12


def validate_geometry(vertices, topology: MeshTopology, rtol: float = 1e-12,
                      laid_out: bool = True) -> None:
    """Check vertex positions (V, d), d = 2 or 3, against ``topology``; return None or raise.
    `laid_out`: the faces' layouts come from these positions (False: the current positions
    of a surface bound to another rest shape, which it only moves linearly), so faces whose
    edge lengths admit no convex polygon are degenerate too (:func:`flat_faces`).

    Tags in the module docstring. ``zero_length_edge``: |x_a - x_b| <= rtol * median edge
    length (element vertex, the end points, ``err.edges`` the pairs);
    ``degenerate_face``: |vector area| <= rtol * (longest edge of the face)**2 (element
    face; the vector area sum_k x_k x x_{k+1} / 2 vanishes exactly for collinear
    corners and for self-cancelling polygons).
    """
    if not isinstance(topology, MeshTopology):
        raise InvalidParameterError("topology", f"must be a MeshTopology (e.g. "
                                    f"MeshTopology(faces, n_vertices)), got "
                                    f"{type(topology).__name__}")
    x = np.asarray(vertices)
    if x.ndim != 2 or x.shape[1] not in (2, 3) or x.shape[0] != topology.n_vertices \
            or x.dtype.kind not in "fiu":
        raise InvalidMeshError("bad_shape", f"bad_shape: vertices must be a real ({topology.n_vertices}"
                               f", 3) array, got shape {x.shape} dtype {x.dtype}", None, "vertex")
    x = x.astype(np.float64)  # a copy
    if x.shape[1] == 2:
        x = np.concatenate([x, np.zeros((len(x), 1))], 1)
    check_finite(x)
    e = topology.edges
    length, scale = check_outliers(x, e)
    short = length <= rtol * scale
    if short.any():
        raise edge_error("zero_length_edge", f"have length <= {rtol:g} * the median edge length",
                          e[short], topology.edge_faces[short][topology.edge_faces[short] >= 0])
    flat = flat_faces(x, topology.face_sizes, topology.face_vertices, rtol, laid_out)
    if flat.any():
        raise InvalidMeshError("degenerate_face", "degenerate_face: zero area (collinear "
                               "corners) in faces", np.flatnonzero(flat), "face")


def check_outliers(x, edges, scale=None) -> tuple[np.ndarray, float]:
    """Raise ``outlier_vertex`` for the vertices of x (V, 3) whose edges (``edges`` (E, 2),
    each once) are all longer than ``OUTLIER_FACTOR`` times the median edge length; else
    return (the edges' lengths (E,), that median). Checked before the repairs too
    (:func:`gerbs_core.mesh.repair.repair_mesh`): next to a vertex 1e14 away its faces'
    areas vanish to the rounding, and the zero-area repair dropped them silently (a
    newcomer's walk: Blender stores ``co.x = inf`` as 3.4e38). ``scale``: the median edge
    length to compare with, where the caller knows a better one (the repair: of the faces
    with an area, not of slivers it will drop)."""
    length = np.linalg.norm(x[edges[:, 1]] - x[edges[:, 0]], axis=1)
    if scale is None:
        scale = float(np.median(length)) if len(length) else 0.0
    shortest = np.full(len(x), np.inf)
    np.minimum.at(shortest, edges[:, 0], length)
    np.minimum.at(shortest, edges[:, 1], length)
    # (a vertex in no edge, loose or welded away, is no outlier: its shortest stays inf)
    far = (shortest > OUTLIER_FACTOR * scale) & np.isfinite(shortest) & (scale > 0)
    if far.any():
        raise InvalidMeshError("outlier_vertex", f"outlier_vertex: every edge of these vertices "
                               f"is more than {OUTLIER_FACTOR:g} times the median edge length "
                               f"{scale:.3g} (a stray coordinate?); vertices",
                               np.flatnonzero(far), "vertex")
    return length, scale


def check_finite(x, name: str = "vertices") -> None:
    """Raise ``non_finite`` naming the argument ``name`` and the rows of x (V, d) or (V,)
    with NaN or infinite entries (``err.indices``; ``err.name`` = ``name``).

    The one check of every position input: BlendingSurface's ``vertices`` and
    ``rest_positions``, :meth:`~gerbs_core.mesh.surface.BlendingSurface.with_positions`,
    :meth:`~gerbs_core.mesh.stencil.Stencil.apply`. One pass of np.isfinite over x (the
    rows are found only when one fails: a row-wise reduction costs 25x more)."""
    x = np.asarray(x)
    finite = np.isfinite(x)
    if not finite.all():
        nf = ~finite.reshape(len(x), -1).all(axis=1)
        err = InvalidMeshError("non_finite", f"{name}: NaN or infinite coordinates at indices",
                               np.flatnonzero(nf), "vertex")
        err.name = name
        raise err


def corner_successors(sizes) -> np.ndarray:
    """(C,) the next corner of every corner of CSR faces with corner counts ``sizes`` (F,)."""
    sizes = np.asarray(sizes, dtype=np.int64)
    offsets = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    nxt = np.arange(1, int(offsets[-1]) + 1, dtype=np.int64)
    nxt[offsets[1:] - 1] = offsets[:-1]
    return nxt


def not_a_polygon(longest, total) -> np.ndarray:
    """Bool array: faces whose longest edge (`longest`) is not shorter than the sum of the
    others (`total` - `longest`) by a relative margin of ``CHAIN_RTOL`` (arrays of the same
    shape): no convex polygon has these edge lengths (:func:`layout.face_layouts`), and
    the corners lie on a chain along the longest edge, within about
    ``sqrt(CHAIN_RTOL / 2)`` of its length."""
    return ~(2.0 * longest < total * (1.0 - CHAIN_RTOL))


def face_vector_areas(x, sizes, flat) -> np.ndarray:
    """(F, 3) twice the vector areas sum_k (x_k - x_0) x (x_{k+1} - x_0) of CSR faces
    (corner counts ``sizes`` (F,), vertices ``flat`` (C,); positions x (V, 3)), about each
    face's first corner x_0: no cancellation far from the origin (from absolute
    coordinates a 1 cm mesh at 5e5 got NaN normals, a review), and exactly 0 for
    collinear corners and self-cancelling polygons."""
    sizes = np.asarray(sizes, dtype=np.int64)
    cf = np.repeat(np.arange(len(sizes)), sizes)
    first = np.zeros(len(sizes), dtype=np.int64)
    np.cumsum(sizes[:-1], out=first[1:])
    base = x[flat[first[cf]]]
    out = np.zeros((len(sizes), 3))
    np.add.at(out, cf, np.cross(x[flat] - base, x[flat[corner_successors(sizes)]] - base))
    return out


def _edge_sums(x, sizes, flat) -> tuple:
    """((F,) longest, (F,) total) edge lengths of CSR faces, each edge |x_next - x| as the
    layout measures it (:func:`layout.face_layouts`)."""
    sizes = np.asarray(sizes, dtype=np.int64)
    cf = np.repeat(np.arange(len(sizes)), sizes)
    length = np.linalg.norm(x[flat[corner_successors(sizes)]] - x[flat], axis=1)
    longest, total = np.zeros(len(sizes)), np.zeros(len(sizes))
    np.maximum.at(longest, cf, length)
    np.add.at(total, cf, length)
    return longest, total


def chain_faces(x, sizes, flat) -> np.ndarray:
    """(F,) bool: faces (CSR as :func:`flat_faces`) whose edge lengths admit no convex
    polygon (:func:`not_a_polygon`): collinear corners, to the rounding of the positions."""
    return not_a_polygon(*_edge_sums(x, sizes, flat))


def flat_faces(x, sizes, flat, rtol: float = 1e-12, laid_out: bool = True) -> np.ndarray:
    """(F,) bool: faces (CSR: corner counts ``sizes`` (F,), vertices ``flat`` (C,)) of zero
    area, |vector area| <= rtol * (longest edge of the face)**2 (:func:`face_vector_areas`),
    or, where x is the shape the faces are laid out from (`laid_out`), whose edge lengths
    admit no convex polygon (:func:`chain_faces`); positions x (V, 3).

    Collinear corners stored in single precision (Blender's positions) keep an area of
    about 1e-8 of the edge squared, but their edge lengths admit no polygon: found by a
    test with messy meshes, whose T-junction sliver was repaired from float64 positions
    and refused from Blender's."""
    longest, total = _edge_sums(x, sizes, flat)
    zero = 0.5 * np.linalg.norm(face_vector_areas(x, sizes, flat), axis=1) <= rtol * longest ** 2
    return zero | not_a_polygon(longest, total) if laid_out else zero
