"""Creases in the surface construction: the input's crease weights carried through the mesh
repair, the model of the cut mesh, and its outputs merged back onto the mesh.

Vertex layers: input vertices (V) -> repaired vertices (V', :mod:`gerbs_core.mesh.repair`,
``vertex_map``) -> vertex copies of the cut mesh (V'', :mod:`gerbs_core.mesh.creases`,
``copy_of``). Creases are given on the input (vertex pairs, vertex weights) and land on
every repaired edge whose end points come from the pair's vertices (welded vertices: the
pair of their representatives; a split non-manifold edge: all its sheets). Tessellations
and stencils are on the repaired mesh, evaluated on the cut one and merged.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError
from .arrays import ranges
from .agreement import MMAX, fair_fits, tension_weights
from .charts import vertex_charts
from .cover import star_cover
from .crease_fits import corner_scales, curve_constraints
from .creases import crease_cut
from .layout import face_layouts
from .memory import check_build
from .rings import data_rings

__all__ = ["crease_input", "build_model", "first_occurrence", "merge_tessellation",
           "input_edge_weights"]


def _pairs(creases):
    """(pairs (K, 2) int, weights (K,)) from {(i, j): w} or (edges (K, 2), weights (K,))."""
    if isinstance(creases, dict):
        keys, vals = list(creases.keys()), list(creases.values())
    elif isinstance(creases, (tuple, list)) and len(creases) == 2:
        keys, vals = creases
    else:
        raise InvalidParameterError("creases", "must be a mapping {(i, j): weight} of input "
                                    "vertex pairs or a pair (edges (K, 2) int, weights (K,)), "
                                    f"got {type(creases).__name__}")
    try:
        pairs = np.array(keys, dtype=np.float64).reshape(-1, 2) if len(keys) else \
            np.zeros((0, 2))
        w = np.array(vals, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidParameterError("creases", "edges must be (i, j) vertex index pairs and "
                                    "weights numbers") from None
    if len(w) != len(pairs):
        raise InvalidParameterError("creases", f"{len(pairs)} edges but {len(w)} weights")
    if not np.all(pairs == np.round(pairs)):
        raise InvalidParameterError("creases", "edge vertex indices must be integers")
    bad = np.flatnonzero(~(np.isfinite(w) & (w >= 0.0) & (w <= 1.0)))
    if bad.size:
        raise InvalidParameterError("creases", f"weights must lie in [0, 1]; bad at entries "
                                    f"{bad[:10].tolist()}")
    return pairs.astype(np.int64), w


def _input_edges(faces, V):
    """Sorted codes lo * V + hi of the input's edges (consecutive face corners)."""
    from .topology import MeshTopology, _parse_faces
    if isinstance(faces, MeshTopology):
        sizes, flat = np.asarray(faces.face_sizes), np.asarray(faces.face_vertices)
    else:
        sizes, flat = _parse_faces(faces, V)
    off = np.concatenate([[0], np.cumsum(sizes)])
    nxt = np.arange(len(flat)) + 1
    ends = off[1:] - 1
    nxt[ends] = off[:-1]
    a, b = flat, flat[nxt]
    return np.unique(np.minimum(a, b) * V + np.maximum(a, b))


def input_edge_weights(repair, faces, creases) -> np.ndarray:
    """(E',) crease weights of the repaired mesh's edges (``repair.topology.edges``) from the
    input's ``creases`` (see :func:`crease_input`); the largest where several input edges
    land on one repaired edge. Raises InvalidParameterError("creases") for pairs that are
    not edges of the input (or name vertices outside it)."""
    V = len(repair.representative)
    pairs, w = _pairs(creases)
    out = np.zeros(repair.topology.n_edges)
    if not len(pairs):
        return out
    if pairs.min() < 0 or pairs.max() >= V:
        raise InvalidParameterError("creases", f"vertex indices must lie in [0, {V - 1}]")
    lo, hi = pairs.min(1), pairs.max(1)
    codes = _input_edges(faces, V)
    pos = np.clip(np.searchsorted(codes, lo * V + hi), 0, len(codes) - 1)
    bad = codes[pos] != lo * V + hi
    if bad.any():
        raise InvalidParameterError("creases", f"{[tuple(p) for p in pairs[bad][:10].tolist()]}"
                                    f" are not edges of the mesh")
    rep = repair.representative
    a, b = rep[lo], rep[hi]
    a, b = np.minimum(a, b), np.maximum(a, b)
    E = repair.topology.edges
    vm = repair.vertex_map
    ea, eb = vm[E[:, 0]], vm[E[:, 1]]
    ecode = np.minimum(ea, eb) * V + np.maximum(ea, eb)
    order = np.argsort(ecode, kind="stable")
    keys = a * V + b
    first = np.searchsorted(ecode[order], keys, side="left")
    last = np.searchsorted(ecode[order], keys, side="right")
    # every repaired edge of every pair (an input edge split into sheets lands on several)
    n = last - first
    idx = order[ranges(first, n)]
    np.maximum.at(out, idx, np.repeat(w, n))
    return out


def crease_input(repair, faces, creases, corners):
    """The :class:`~gerbs_core.mesh.creases.CreaseCut` of the repaired mesh for the input's
    crease weights, or None without any (all weights 0 or none given).

    creases: None, {(i, j): w} or (edges (K, 2), weights (K,)) over INPUT vertex pairs (either
    order; edges the repair dropped are ignored); corners: None or (V,) input vertex crease
    weights (welded vertices: the largest of the group). Weights in [0, 1]."""
    if creases is None and corners is None:
        return None
    ew = None if creases is None else input_edge_weights(repair, faces, creases)
    vw = None
    if corners is not None:
        V = len(repair.representative)
        try:
            c = np.array(corners, dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidParameterError("corners", f"must be an array of {V} vertex weights, "
                                        f"got {type(corners).__name__}") from None
        if c.shape != (V,):
            raise InvalidParameterError("corners", f"must have shape ({V},) (one weight per "
                                        f"input vertex), got shape {c.shape}")
        if not np.all(np.isfinite(c) & (c >= 0) & (c <= 1)):
            raise InvalidParameterError("corners", "weights must lie in [0, 1]")
        g = np.zeros(V)
        np.maximum.at(g, repair.representative, c)
        vw = g[repair.vertex_map]
    cut = crease_cut(repair.topology, ew, vw)
    return cut if (cut.edge_weight.any() or cut.vertex_weight.any()) else None


def build_model(topo, rest, cut, kernel, boundary, fairness, kappa, shrink, exact_gauge,
                budget):
    """The parts of a SurfaceModel of the cut mesh (layouts, charts, cover, degrees, fits):
    crease chart scales, fixed end-line scales at crease rays, the tension raised at creases
    and the curve constraints (docs/design.md, "Creases"); ``budget``: the memory budget
    the construction is checked against (:func:`gerbs_core.mesh.memory.check_build`)."""
    mtopo, mrest = cut.topology, cut.positions(rest)
    layouts = face_layouts(mtopo, mrest)
    sharp = cut.sharpness(tension_weights(topo, rest, fairness))
    scale = corner_scales(cut, layouts.angles, rest, cut.chart_scales(layouts.angles))
    charts = vertex_charts(mtopo, layouts.corners, layouts.angles, boundary, scale)
    cover = star_cover(mtopo, charts, layouts.corners, kernel, kappa, shrink, exact_gauge,
                       cut.crease_ends())
    rings = data_rings(mtopo, charts, layouts.corners)
    check_build(mtopo.face_sizes, budget, len(rings.ids))
    cons = None
    if cut.any_cut:
        def cons(degrees):
            return curve_constraints(cut, charts, rest, degrees, MMAX)
    degrees, fits = fair_fits(mtopo, charts, layouts.corners, cover, rings, mrest, fairness,
                              sharp, cons)
    degrees.flags.writeable = False
    return layouts, charts, cover, degrees, fits


def first_occurrence(m, n):
    """(n,) the first index i with m[i] = j, for every j in [0, n) (m covers all of them)."""
    rep = np.empty(n, dtype=np.int64)
    rep[m[::-1]] = np.arange(len(m) - 1, -1, -1)
    return rep


def merge_tessellation(cut, mlat, lat, S, nrm):
    """Points and normals of the cut mesh's lattice ``mlat`` merged onto the mesh's ``lat``:
    the two sides of a crease give the same points to rounding (the first is kept); the
    normal there is the mean of the sides' (the surface has no tangent plane on a crease)."""
    m = cut.sample_map(mlat)
    S = S[first_occurrence(m, lat.n_points)]
    merged = np.zeros((lat.n_points, 3))
    np.add.at(merged, m, nrm)
    ln = np.linalg.norm(merged, axis=1)
    return S, merged / np.where(ln > 0, ln, 1.0)[:, None]
