"""Mesh repair in front of the surface construction: any polygon soup a modeller has
becomes an oriented 2-manifold with boundary, plus the maps back to the input and
warnings naming what was changed.

    repaired = repair_mesh(vertices, faces, merge_distance=None)
    repaired.topology        # MeshTopology of the repaired mesh (V' vertices, F' faces)
    repaired.vertices        # (V', 3) = vertices[repaired.vertex_map]
    repaired.vertex_map      # (V',) input vertex of every repaired vertex (non-decreasing)
    repaired.face_map        # (F',) input face every repaired face comes from
    repaired.warnings        # tuple of MeshWarning, in the order of the stages below

The rules, stage by stage (tags as in :class:`gerbs_core.errors.InvalidMeshError`;
geometric tests use the rest shape when one is given):

1. ``merged_vertices`` (only with ``merge_distance``): vertices within that distance of
   each other (transitively; 0 = coincident ones) become one, the lowest index, at its
   position (as Blender's Merge by Distance). ``zero_length_edge``: the end points of
   an edge no longer than ``rtol`` median edge lengths are welded likewise.
2. ``repeated_index``: repeated consecutive corners are collapsed; a face that revisits
   a vertex is cut there into simple loops (orientation kept). ``loose_edge``: faces
   of two vertices, and ``degenerate_face``: faces left with fewer than 3 vertices, are
   ignored. ``duplicate_face``: faces with the vertex set of an earlier face are dropped.
3. ``zero_area_face``: collinear faces are merged into the face across their longest
   edge (the surface closes over them, through all their vertices); where that is not
   possible (a boundary edge, a self-cancelling polygon) they are dropped
   (``degenerate_face``) and the surface is bounded by their neighbours.
   ``concave_face``: a face of 5 or more corners whose corners turn back by more than 10
   degrees in all, in its plane, is split along diagonals into convex faces
   (:mod:`gerbs_core.mesh.repair_concave`: a face is laid out as a convex polygon, and the
   surface folds at a reflex corner).
4. ``non_manifold_edge``: an edge of 3 or more faces is split into manifold sheets
   (:mod:`gerbs_core.mesh.repair_sheets`): faces are paired by consistent orientation
   and angle, so the smoothest continuations stay glued (the plane of a T-junction is
   one smooth sheet, its fin a sheet with the edge as boundary); paired faces are C^inf
   across the edge, and the sheets meet at the edge's vertices.
5. ``inconsistent_orientation``: faces are flipped to agree with their neighbours (the
   fewer of each piece); ``non_orientable``: edges cut open where no orientation exists.
6. ``non_manifold_vertex``: a vertex whose faces form several fans (a bow-tie, or the
   end of a split edge) gets one copy per fan; the surface passes through it once per
   fan and the output has one vertex sample per copy.
7. ``unused_vertex``: vertices in no (remaining) face are ignored: not in the surface
   and not in its output (``vertex_map`` does not name them).
8. ``open_seam``: boundary vertices at the position of another boundary vertex (an
   export split at UV seams or sharp normals) are not joined: the surface has a crack
   there; ``merge_distance`` welds them.

Refused (InvalidMeshError), because no surface can come from them: ``bad_shape``,
``empty`` (no faces, no vertices, or nothing left after stage 3), ``index_out_of_range``
(a face naming a vertex that does not exist), ``non_finite`` (NaN or infinite
coordinates, loose vertices included) and ``outlier_vertex`` (a vertex of a face 1e6
median edge lengths from the rest: float64 cannot hold both scales). A mesh that only
``merge_distance`` empties (welding collapsed every face that would otherwise be left) is
refused as that setting's error (InvalidParameterError naming ``merge_distance``), not as
an empty mesh.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidMeshError, _short
from ..immutable import ReadOnlyArrays
from . import repair_concave as rc
from . import repair_faces as rf
from . import repair_sheets as rs
from .selection import selection_matrix
from .topology import MeshTopology, _parse_faces
from .validation import (check_finite, check_outliers, corner_successors, flat_faces,
                         validate_geometry)

__all__ = ["MeshWarning", "RepairedMesh", "repair_mesh"]

SEAM_RTOL = 1e-6  # boundary vertices closer than 1e-6 median edge lengths coincide

_TEXT = {
    "merged_vertices": "merged by distance: vertices welded into the lowest-index vertex of "
                       "their cluster, at its position",
    "zero_length_edge": "zero-length edges: their end points welded into one vertex",
    "repeated_index": "faces naming a vertex twice: repeated corners collapsed, a face that "
                      "revisits a vertex cut into simple loops",
    "loose_edge": "two-vertex faces (loose edges): ignored by the surface",
    "degenerate_face": "faces with fewer than 3 distinct vertices or zero area that no "
                       "neighbour can absorb: dropped, the surface is bounded by their "
                       "neighbours",
    "duplicate_face": "faces with the vertices of an earlier face: dropped",
    "zero_area_face": "zero-area (collinear) faces merged into the face across their longest "
                      "edge: the surface closes over them",
    "concave_face": "concave n-gons (turning back by more than 10 degrees in all) split into "
                    "convex faces along diagonals: the surface is smooth across them",
    "non_manifold_edge": "edges of 3 or more faces split into manifold sheets (faces paired "
                         "by orientation and angle, an unpaired face has the edge as a "
                         "boundary)",
    "inconsistent_orientation": "faces flipped to agree with the orientation of their "
                                "neighbours",
    "non_orientable": "no orientation exists: edges cut open (a boundary on both sides)",
    "non_manifold_vertex": "vertices where several fans of faces meet: the surface passes "
                           "through each once per fan (one output vertex per fan; see "
                           "vertex_map)",
    "unused_vertex": "vertices in no face (loose vertices, ends of loose edges): ignored by "
                     "the surface and left out of its output",
    "open_seam": "boundary vertices at the position of other boundary vertices (an unwelded "
                 "seam, e.g. split UVs or normals of an export): the surface is open there; "
                 "merge_distance welds them",
    # not a repair: BlendingSurface(normals=) at kept vertices given a zero normal
    "zero_normal": "no normal given (zero length): the surface's tangent plane there is fitted",
}
ORDER = tuple(_TEXT)


@dataclass(frozen=True)
class MeshWarning:
    """One repair of the input mesh: ``tag`` (see :mod:`gerbs_core.mesh.repair`),
    ``message`` (one line naming the first indices), ``indices`` (sorted input indices of
    ``element`` "vertex" or "face"), ``edges`` ((a, b) input vertex pairs, edge tags)."""

    tag: str
    message: str
    indices: tuple
    element: str
    edges: tuple = ()

    def __str__(self):
        return self.message


@dataclass(frozen=True)
class RepairedMesh(ReadOnlyArrays):
    """The result of :func:`repair_mesh` (module docstring). ``representative (V,)``:
    the input vertex each input vertex was welded to (itself if none)."""

    topology: MeshTopology
    vertices: np.ndarray
    rest: np.ndarray | None
    vertex_map: np.ndarray
    face_map: np.ndarray
    representative: np.ndarray
    warnings: tuple
    changed: bool  # False: the repaired mesh is the input (identity maps, same faces)

    def positions(self, X) -> np.ndarray:
        """Input positions (V, 3) -> the repaired vertices' (V', 3)."""
        return np.asarray(X, dtype=np.float64)[self.vertex_map]

    def to_input(self, m):
        """A sparse map from the repaired vertices' positions ((N, V') matrix) composed
        with the selection of them from the input's: the same map of the input (N, V)."""
        if not self.changed:
            return m
        return (m @ selection_matrix(self.vertex_map, len(self.representative))).tocsr()

    def fits_of_input(self, fits):
        """The coefficient map ``fits`` (:class:`~gerbs_core.mesh.coupling.CoupledFits`,
        of the repaired vertices) as a map of the input's positions (same interface)."""
        from .coupling import SelectedFits
        return fits if not self.changed else SelectedFits(fits, self.vertex_map,
                                                          len(self.representative))


def _warning(tag, indices, element, detail=None):
    idx = tuple(int(i) for i in np.unique(np.asarray(indices, dtype=np.int64)))
    edges = () if detail is None or isinstance(detail, str) else \
        tuple((int(a), int(b)) for a, b in np.asarray(detail).reshape(-1, 2).tolist())
    what = f"; edges {', '.join(map(str, edges[:5]))}{' ...' if len(edges) > 5 else ''}" \
        if edges else ""
    text = f"{tag}: {_TEXT[tag]}{what}; {element} indices{_short(idx)}"
    return MeshWarning(tag, text, idx, element, edges)


def _combined(notes):
    """One note per tag (indices and edge pairs joined), in the order of ``ORDER``."""
    out = []
    for tag in ORDER:
        mine = [n for n in notes if n[0] == tag]
        if mine:
            edges = [np.asarray(n[3]).reshape(-1, 2) for n in mine
                     if n[3] is not None and not isinstance(n[3], str)]
            out.append((tag, np.concatenate([np.asarray(n[1]).ravel() for n in mine]),
                        mine[0][2], np.unique(np.concatenate(edges), axis=0) if edges else None))
    return out


def _parse(X, faces):
    if isinstance(faces, MeshTopology):
        if faces.n_vertices != len(X):
            from ..errors import InvalidParameterError
            raise InvalidParameterError("vertices", f"must have {faces.n_vertices} rows (the "
                                        f"topology's vertices), got {len(X)}")
        return np.array(faces.face_sizes), np.array(faces.face_vertices)
    sizes, flat = _parse_faces(faces, len(X))
    bad = (flat < 0) | (flat >= len(X))
    if bad.any():
        cface = np.repeat(np.arange(len(sizes)), sizes)
        raise InvalidMeshError("index_out_of_range", f"index_out_of_range: vertex indices "
                               f"{np.unique(flat[bad])[:10].tolist()} are outside "
                               f"[0, {len(X) - 1}] in faces", np.unique(cface[bad]), "face")
    return sizes, flat


def _topology_repairs(G, sizes, flat, notes):
    """Stages 4-6: (flat in new vertex numbers, vertex_map, partner)."""
    partner, bad_edges, _ = rs.glue(G, sizes, flat)
    if len(bad_edges):
        notes.append(("non_manifold_edge", np.unique(bad_edges), "vertex", bad_edges))
    flip, cut = rs.orient(sizes, flat, partner)
    if len(cut):
        cut_edges = np.sort(np.stack([flat[cut], flat[partner[cut]]], 1), axis=1)
        partner[cut] = -1
        notes.append(("non_orientable", np.unique(cut_edges), "vertex", np.unique(cut_edges, axis=0)))
    flat, partner = rs.flip_faces(sizes, flat, partner, flip)
    prv = np.empty_like(flat)
    prv[corner_successors(sizes)] = np.arange(len(flat))
    for _ in range(len(flat) + 1):  # each round cuts at least one glue
        label = rs.fans(sizes, flat, partner)
        keys, new_flat = np.unique(flat * len(flat) + label, return_inverse=True)
        new_flat = new_flat.reshape(-1)
        groups = rs.conflicts(sizes, new_flat, partner)
        if not groups:
            break
        for hs in groups:  # keep one glued pair, detach the other corners at their start
            keep = [h for h in hs if partner[h] in hs][:1]
            keep = keep + [int(partner[keep[0]])] if keep else [hs[0]]
            for h in hs:
                if h not in keep:
                    for c in (h, prv[h]):
                        if partner[c] >= 0:
                            partner[partner[c]] = -1
                            partner[c] = -1
    return new_flat, keys // len(flat), partner, flip


def _open_seams(G, vertex_map, sizes, flat, partner):
    """Boundary vertices coinciding with a boundary vertex of another input vertex."""
    from scipy.spatial import cKDTree

    nxt = corner_successors(sizes)
    bh = np.flatnonzero(partner < 0)
    if not len(bh):
        return None
    bv = np.unique(np.r_[flat[bh], flat[nxt[bh]]])
    e = np.stack([flat[nxt], flat], 1)
    scale = float(np.median(np.linalg.norm(G[e[:, 0]] - G[e[:, 1]], axis=1)))
    pairs = cKDTree(G[bv]).query_pairs(SEAM_RTOL * scale, output_type="ndarray")
    pairs = bv[pairs.reshape(-1, 2)]
    pairs = pairs[vertex_map[pairs[:, 0]] != vertex_map[pairs[:, 1]]]
    if not len(pairs):
        return None
    seam = np.zeros(int(flat.max()) + 1, dtype=bool)
    seam[pairs.ravel()] = True
    edges = np.sort(vertex_map[np.stack([flat[bh], flat[nxt[bh]]], 1)], axis=1)
    edges = np.unique(edges[seam[flat[bh]] & seam[flat[nxt[bh]]]], axis=0)
    return np.unique(vertex_map[pairs]), edges


def _area_scale(G, sizes, flat, bad) -> float | None:
    """The median edge length of the faces with an area (``bad`` (F,): those without one;
    None where none has one, or all do: the caller's own median then)."""
    if not bad.any() or bad.all():
        return None
    keep = np.repeat(~bad, sizes)
    e = rf.unique_edges(sizes[~bad], flat[keep], len(G))
    return float(np.median(np.linalg.norm(G[e[:, 0]] - G[e[:, 1]], axis=1)))


def _faces_without_merge(G, sizes0, flat0, rtol) -> bool:
    """Would faces with an area be left without welding? (Only to say why a mesh came out
    empty: the same stages as :func:`repair_mesh` with ``merge_distance=None``.)"""
    rep = rf.weld_map(G, sizes0, flat0, None, rtol, [])
    sizes, flat, origin = rf.clean_faces(sizes0, rep[flat0], np.arange(len(sizes0)), sizes0,
                                         rf.input_repeats(sizes0, flat0), [])
    if len(sizes):
        sizes, flat, origin = rf.merge_zero_area(G, sizes, flat, origin,
                                                 flat_faces(G, sizes, flat, rtol), [])
    return bool(len(sizes))


def repair_mesh(vertices, faces, *, merge_distance=None, rest_positions=None,
                rtol: float = 1e-12) -> RepairedMesh:
    """Repair a polygon mesh into an oriented 2-manifold with boundary (module docstring).

    vertices (V, 3) float; faces: int sequences, an (F, k) int array or a MeshTopology;
    merge_distance: None (off) or a distance >= 0 in the units of the vertices;
    rest_positions (V, 3): the shape the geometric tests use (default: vertices).
    Raises InvalidMeshError for what no surface can come from, InvalidParameterError for a
    merge_distance that collapses every face; never modifies its input.
    """
    X = np.asarray(vertices, dtype=np.float64)
    check_finite(X)
    R = None if rest_positions is None else np.asarray(rest_positions, dtype=np.float64)
    if R is not None:
        check_finite(R, "rest_positions")
    G = X if R is None else R
    if merge_distance is not None and not (isinstance(merge_distance, (int, float, np.number))
                                           and np.isfinite(merge_distance) and merge_distance >= 0):
        from ..errors import InvalidParameterError
        raise InvalidParameterError("merge_distance", f"must be None or a finite distance "
                                    f">= 0, got {merge_distance!r}")
    sizes0, flat0 = _parse(X, faces)
    V, notes = len(X), []
    rep = rf.weld_map(G, sizes0, flat0, merge_distance, rtol, notes)
    sizes, flat, origin = rf.clean_faces(sizes0, rep[flat0], np.arange(len(sizes0)), sizes0,
                                         rf.input_repeats(sizes0, flat0), notes)
    if len(sizes):
        # a stray coordinate first: its faces would otherwise pass for zero-area ones below;
        # measured against the edges of the faces with an area (a review: 60 collapsed
        # slivers beside a grid made the median 2e-9 and every real vertex an outlier)
        bad = flat_faces(G, sizes, flat, rtol)
        check_outliers(G, rf.unique_edges(sizes, flat, V), _area_scale(G, sizes, flat, bad))
        sizes, flat, origin = rf.merge_zero_area(G, sizes, flat, origin, bad, notes)
        sizes, flat, origin = rc.split_concave(G, sizes, flat, origin, notes)
    if not len(sizes):
        if merge_distance is not None and _faces_without_merge(G, sizes0, flat0, rtol):
            from ..errors import InvalidParameterError
            raise InvalidParameterError("merge_distance", (
                f"merging vertices closer than {merge_distance:g} collapsed every face; use a "
                f"smaller merge_distance"))
        raise InvalidMeshError("empty", "empty: no face with 3 distinct vertices and an area "
                               "(every face is degenerate)", None, "face")
    new_flat, vmap, partner, flip = _topology_repairs(G, sizes, flat, notes)
    if flip.any():
        notes.append(("inconsistent_orientation", origin[flip], "face", None))
    copies = np.bincount(vmap, minlength=V)
    if (copies > 1).any():
        notes.append(("non_manifold_vertex", np.flatnonzero(copies > 1), "vertex", None))
    unused = (copies == 0) & (rep == np.arange(V))
    if unused.any():
        notes.append(("unused_vertex", np.flatnonzero(unused), "vertex", None))
    seams = _open_seams(G[vmap], vmap, sizes, new_flat, partner)
    if seams is not None:
        notes.append(("open_seam", seams[0], "vertex", seams[1]))
    notes = _combined(notes)
    changed = bool(len(vmap) != V or len(sizes) != len(sizes0) or not np.array_equal(
        new_flat, flat0))
    if not changed and isinstance(faces, MeshTopology):
        topo = faces
    else:
        topo = MeshTopology.from_csr(sizes, new_flat, len(vmap))
    Xn = X[vmap]
    Rn = None if R is None else R[vmap]
    validate_geometry(Xn if Rn is None else Rn, topo, rtol)
    if Rn is not None:
        # (only moved linearly: a nearly flat current shape is fine, found by a review: a
        # Bound patch squashed to 1e-6 was refused as collinear)
        validate_geometry(Xn, topo, rtol, laid_out=False)
    for a in (Xn, vmap, origin, rep) + (() if Rn is None else (Rn,)):
        a.flags.writeable = False
    return RepairedMesh(topo, Xn, Rn, vmap, origin, rep, tuple(_warning(*n) for n in notes),
                        changed)
