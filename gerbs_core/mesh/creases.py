"""Creases as a topology step: cut the mesh along its fully creased edges.

Blender-style crease weights (edge creases w_e in [0, 1], vertex creases w_v in
[0, 1]) shape the surface in two ways (docs/design.md, "Creases"):

* a *fully creased* edge (w_e = 1) is cut: every vertex gets one copy per fan of
  faces between its creased edges, so the surface is built on a mesh with
  boundaries (:attr:`CreaseCut.topology`) and is C0 across the cut, with a normal
  jump. The two sides share their output samples along the cut edge
  (:meth:`CreaseCut.sample_map`): the surface agrees there because the partition
  (fixed end-line scales, :mod:`gerbs_core.gauge.blend`) and the local functions
  (curve constraints, :mod:`gerbs_core.mesh.crease_fits`) are side-independent.
* partial weights (0 < w < 1, and full creases that cannot be cut) and vertex creases
  tighten the surface near them through the tension energy of the fair-shape rule
  (:meth:`CreaseCut.sharpness`): a proportionally tighter, still C-infinity surface.

Chains: the cut edges form chains between *corners* (vertices with >= 3 cut edges,
two cut edges and a vertex crease of 1, or cut edges at the mesh boundary); a chain
without corners is a closed loop. A vertex with a single cut edge away from the
border is a *dart*: the crease fades out there (its chart is the full disc, as
for an interior vertex), like Catmull-Clark's dart rule. An edge both of whose
ends would be darts cannot be cut (a slit without a split vertex is not a
2-manifold with boundary); it is treated as a partial crease of weight 1.

Vertex roles (per copy, :attr:`CreaseCut.role`): ``SMOOTH`` (not at a cut),
``CHAIN`` (two rays of one chain: the chart is straightened so that they are
antiparallel and the crease curve keeps one tangent), ``CORNER`` (rays of
different chains, or a chain and the mesh border: the chart keeps its angles),
``DART`` (the full-disc chart).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ..errors import InvalidParameterError
from .topology import MeshTopology
from .selection import selection_matrix

__all__ = ["CreaseCut", "crease_cut", "crease_weights", "vertex_weights", "FULL",
           "SMOOTH", "CHAIN", "CORNER", "DART"]

FULL = 1.0 - 1e-6          # a weight at least this is a full crease (Blender stores float32)
SMOOTH, CHAIN, CORNER, DART = 0, 1, 2, 3

# sharpness added per unit of crease weight. Measured (mean distance of the creased edges'
# samples to their cage edges, w = 0, .25, .5, .75, .99): a UV sphere's latitude loop
# .0123 .0111 .0104 .0097 .0092, one cube edge .116 .099 .085 .073 .063, monotone; with a
# gain of 3 or 8 the cube edge turns back up above w = .5 (the whole faces pulled flat).
TENSION_GAIN = 1.0

# the weight a cut edge counts with in the tension. Without any, a crease where the mesh is
# smooth hardly shows; with the full weight it dents the faces beside it. Measured on a
# creased UV sphere loop (normal jump across it at resolution 16 / 32, radius spread of the
# surface; uncreased 0.0002): 0 -> 2.5 / 1.9 degrees, 0.0005; 0.1 -> 8.9 / 8.6, 0.0020;
# 0.3 -> 13.9 / 13.9, 0.0030; 1 -> 23.7 / 24.5, 0.0051.
CUT_TENSION = 0.3


def _weights_array(name, values, n, what):
    try:
        w = np.array(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(name, f"must be an array of {n} weights (one per {what}) "
                                    f"or a mapping, got {type(values).__name__}") from None
    if w.shape != (n,):
        raise InvalidParameterError(name, f"must have shape ({n},) (one weight per {what}), "
                                    f"got shape {w.shape}")
    bad = np.flatnonzero(~(np.isfinite(w) & (w >= 0.0) & (w <= 1.0)))
    if bad.size:
        raise InvalidParameterError(name, f"weights must lie in [0, 1]; bad at {what}s "
                                    f"{bad[:10].tolist()}")
    return w


def crease_weights(topo: MeshTopology, creases) -> np.ndarray:
    """Edge crease weights (E,) in [0, 1] aligned with ``topo.edges``, from an (E,) array or
    a mapping {(i, j): w} over mesh edges (either vertex order). Raises
    InvalidParameterError("creases", ...) naming what is wrong."""
    E = topo.n_edges
    if creases is None:
        return np.zeros(E)
    if isinstance(creases, dict):
        w = np.zeros(E)
        if not creases:
            return w
        try:
            keys = np.array([tuple(k) for k in creases], dtype=np.int64).reshape(-1, 2)
        except (TypeError, ValueError):
            raise InvalidParameterError("creases", "mapping keys must be vertex pairs "
                                        "(i, j)") from None
        vals = _weights_array("creases", list(creases.values()), len(keys), "key")
        lo, hi = keys.min(1), keys.max(1)
        V = topo.n_vertices
        code = topo.edges[:, 0] * V + topo.edges[:, 1]
        key = lo * V + hi
        pos = np.searchsorted(code, key)
        ok = (lo >= 0) & (hi < V) & (pos < E)
        ok[ok] = code[pos[ok]] == key[ok]
        if not ok.all():
            bad = [tuple(k) for k in keys[~ok][:10].tolist()]
            raise InvalidParameterError("creases", f"keys {bad} are not edges of the mesh")
        w[pos] = vals
        return w
    return _weights_array("creases", creases, E, "edge")


def vertex_weights(topo: MeshTopology, corners) -> np.ndarray:
    """Vertex crease weights (V,) in [0, 1] (``corners``; None -> zeros)."""
    if corners is None:
        return np.zeros(topo.n_vertices)
    return _weights_array("corners", corners, topo.n_vertices, "vertex")


def _cut_counts(topo, cut):
    """(V,) number of cut spokes at each vertex, and whether the vertex gets split."""
    k = np.bincount(topo.edges[cut].ravel(), minlength=topo.n_vertices)
    split = np.where(topo.vertex_is_boundary, k >= 1, k >= 2)
    return k, split


def _cuttable(topo, full):
    """The full creases that can be cut: at least one end is split (else the slit has no
    split vertex); iterated, since dropping an edge lowers its ends' counts."""
    cut = full.copy()
    while True:
        _, split = _cut_counts(topo, cut)
        ok = split[topo.edges[:, 0]] | split[topo.edges[:, 1]]
        drop = cut & ~ok
        if not drop.any():
            return cut
        cut &= ~drop


def _copies(topo, cut):
    """Copy id of every corner (C,) and copy_of (V',): the fans between cut spokes. The
    first fan of vertex v keeps the id v; further fans get V, V+1, ..."""
    so, sc = topo.star_offsets, topo.star_corners
    he_edge, prv = topo.halfedge_edge, topo.corner_prev
    V = topo.n_vertices
    corner_copy = topo.face_vertices.copy()
    copy_of = list(range(V))
    _, split = _cut_counts(topo, cut)
    for v in np.flatnonzero(split).tolist():
        star = sc[so[v]:so[v + 1]]
        # spoke after star corner j (between j and j + 1): the incoming half-edge of j
        after = cut[he_edge[prv[star]]]
        if not topo.vertex_is_boundary[v]:
            # rotate so that the first fan starts right after a cut spoke
            j = int(np.flatnonzero(after)[-1])
            star = np.roll(star, -(j + 1))
            after = np.roll(after, -(j + 1))
        ids, cur = [], v
        for c, a in zip(star.tolist(), after.tolist()):
            ids.append(cur)
            if a:
                cur = len(copy_of)
                copy_of.append(v)
        if not topo.vertex_is_boundary[v]:
            copy_of.pop()               # the last cut closes the cycle: no new fan after it
        corner_copy[star] = ids
    return corner_copy, np.array(copy_of, dtype=np.int64)


def _chains(topo, cut, corner_vertex):
    """Chains of cut edges: a list of (vertices (n,), edges (n-1,) or (n,) closed, closed)."""
    E = topo.edges
    deg = np.bincount(E[cut].ravel(), minlength=topo.n_vertices)
    adj = {}
    for e in np.flatnonzero(cut).tolist():
        a, b = E[e]
        adj.setdefault(int(a), []).append((int(b), e))
        adj.setdefault(int(b), []).append((int(a), e))
    stop = (deg != 2) | corner_vertex
    used = np.zeros(len(E), dtype=bool)
    out = []

    def walk(v, e):
        vs, es = [v], []
        while True:
            used[e] = True
            es.append(e)
            a, b = E[e]
            v = int(b if a == v else a)
            vs.append(v)
            if stop[v]:
                return vs, es, False
            nxt = [(w, f) for w, f in adj[v] if not used[f]]
            if not nxt:
                return vs[:-1], es, True     # back at the start of a loop
            e = nxt[0][1]

    for v in sorted(adj):
        if stop[v]:
            for _, e in adj[v]:
                if not used[e]:
                    out.append(walk(v, e))
    for v in sorted(adj):
        for _, e in adj[v]:
            if not used[e]:
                out.append(walk(v, e))
    return [(np.array(vs), np.array(es), closed) for vs, es, closed in out]


@dataclass(frozen=True)
class CreaseCut:
    """The mesh cut along its full creases (module docstring). Immutable.

    ``original`` and ``topology`` (the cut mesh, the same faces and corners, vertex ids
    replaced by copies: ``copy_of`` (V',), copies [0, V) are the original vertices);
    ``edge_weight`` (E,), ``vertex_weight`` (V,) the crease weights; ``cut`` (E,) the
    edges cut; ``chains`` list of (vertices, edges, closed); ``role`` (V',) per copy;
    ``corner`` (V,) the corners of the chains.
    """

    original: MeshTopology
    topology: MeshTopology
    copy_of: np.ndarray
    edge_weight: np.ndarray
    vertex_weight: np.ndarray
    cut: np.ndarray
    chains: list
    corner: np.ndarray
    role: np.ndarray

    @property
    def any_cut(self) -> bool:
        return bool(self.cut.any())

    def positions(self, X) -> np.ndarray:
        """Positions of the copies (V', k) from those of the vertices (V, k)."""
        return np.asarray(X)[self.copy_of]

    @cached_property
    def copy_matrix(self) -> sp.csr_matrix:
        """(V', V) 0/1: copy i is vertex copy_of[i] (X' = copy_matrix @ X)."""
        return selection_matrix(self.copy_of, self.original.n_vertices)

    def sharpness(self, base: np.ndarray) -> np.ndarray:
        """Face sharpness (F,) for the tension energy: base + TENSION_GAIN * w, w the largest
        crease weight of the face's edges and its vertices (added, not max(base, w): faces
        the rest shape already makes fully sharp, a cube's, get tighter with w too); cut
        edges count CUT_TENSION (see there)."""
        topo = self.original
        w = np.zeros(topo.n_faces)
        ew = np.where(self.cut, CUT_TENSION, 1.0) * self.edge_weight
        ef = topo.edge_faces
        for k in (0, 1):
            has = ef[:, k] >= 0
            np.maximum.at(w, ef[has, k], ew[has])
        np.maximum.at(w, topo.corner_face, self.vertex_weight[topo.face_vertices])
        return np.asarray(base, dtype=np.float64) + TENSION_GAIN * w

    def chart_scales(self, angles) -> np.ndarray:
        """(V',) chart angle scales of the copies (nan: the boundary rule's): CHAIN copies
        pi / T (the chain's two rays antiparallel), DART copies 2 pi / T (the full disc: the
        slit's two rays coincide); ``angles`` (C,) the layouts' corner angles."""
        T = self.topology
        span = np.bincount(T.face_vertices, angles, minlength=T.n_vertices)
        out = np.full(T.n_vertices, np.nan)
        out[self.role == CHAIN] = np.pi / span[self.role == CHAIN]
        out[self.role == DART] = 2.0 * np.pi / span[self.role == DART]
        return out

    def crease_ends(self) -> np.ndarray:
        """(V', 2) bool: the copy's open fan starts / ends at a cut crease (its first corner's
        outgoing, its last corner's incoming half-edge is a cut edge)."""
        T, O = self.topology, self.original
        so, sc = T.star_offsets, T.star_corners
        out = np.zeros((T.n_vertices, 2), dtype=bool)
        b = np.flatnonzero(T.vertex_is_boundary)
        out[b, 0] = self.cut[O.halfedge_edge[sc[so[b]]]]
        out[b, 1] = self.cut[O.halfedge_edge[T.corner_prev[sc[so[b + 1] - 1]]]]
        return out

    def sample_map(self, cut_lattice) -> np.ndarray:
        """(P',) the sample of the original mesh's lattice (same resolution) of every sample
        of the cut mesh's lattice: copies -> their vertex, the two sides of a cut edge -> one
        edge sample, face interiors shifted. Merged numbering = ``Lattice(original, r)``."""
        r = cut_lattice.resolution
        T, O = self.topology, self.original
        Vc, Ec, V, E = T.n_vertices, T.n_edges, O.n_vertices, O.n_edges
        out = np.empty(cut_lattice.n_points, dtype=np.int64)
        out[:Vc] = self.copy_of
        e = O.halfedge_edge[T.edge_halfedges[:, 0]]           # original edge of each cut edge
        fwd = self.copy_of[T.edges[:, 0]] == O.edges[e, 0]
        m = np.arange(r - 1)
        pos = np.where(fwd[:, None], m[None, :], r - 2 - m[None, :])
        out[Vc:Vc + Ec * (r - 1)] = (V + e[:, None] * (r - 1) + pos).ravel()
        out[Vc + Ec * (r - 1):] = V + E * (r - 1) + np.arange(cut_lattice.n_points - Vc
                                                              - Ec * (r - 1))
        return out


def crease_cut(topo: MeshTopology, creases=None, corners=None) -> CreaseCut:
    """Cut ``topo`` along its full creases (module docstring). ``creases``: (E,) weights
    aligned with ``topo.edges`` or {(i, j): w}; ``corners``: (V,) vertex crease weights."""
    ew = crease_weights(topo, creases)
    vw = vertex_weights(topo, corners)
    bnd = np.asarray(topo.vertex_is_boundary, bool)
    cut = _cuttable(topo, (ew >= FULL) & ~np.asarray(topo.edge_is_boundary, bool))
    k, _ = _cut_counts(topo, cut)
    corner = (k >= 3) | ((k == 2) & (vw >= FULL)) | ((k >= 1) & bnd)
    if cut.any():
        corner_copy, copy_of = _copies(topo, cut)
        sizes = topo.face_sizes
        faces = np.split(corner_copy, topo.face_offsets[1:-1])
        cut_topo = MeshTopology([f.tolist() for f in faces] if len(set(sizes.tolist())) > 1
                                else corner_copy.reshape(-1, int(sizes[0])), len(copy_of))
    else:
        copy_of = np.arange(topo.n_vertices)
        cut_topo = topo
    chains = _chains(topo, cut, corner)
    a = copy_of
    role = np.full(len(copy_of), SMOOTH, dtype=np.int64)
    role[(k[a] == 1) & ~bnd[a]] = DART
    role[(k[a] == 2) & ~corner[a]] = CHAIN
    role[corner[a]] = CORNER
    for arr in (copy_of, ew, vw, cut, corner, role):
        arr.flags.writeable = False
    return CreaseCut(topo, cut_topo, copy_of, ew, vw, cut, chains, corner, role)
