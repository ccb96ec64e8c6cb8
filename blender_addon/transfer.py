"""Carrying the input's attributes to the output surface (numpy only, no bpy).

Every output element lies in one input face at known parameters of the surface's
own parametrization (:class:`gerbs_core.mesh.lattice.Lattice`), so each carried
layer (:mod:`attributes`) is mapped by the rule of its domain:

* face corners (UV maps, corner colors, ...): each output corner lies in one input
  face; its value is the blend of that face's corner values with the corner
  weights of its lattice point (``Lattice.corner_weights``: bilinear in quads,
  barycentric in triangles and n-gon fans). Exact at the input's face corners and
  per face, so UV seams and islands stay as they are;
* vertices (vertex colors, custom values, vertex-group weights): through the
  surface's own linear map of vertex values (``Stencil.apply``, the same map that
  gives the positions): equal at the vertices, smooth between them. Vertex-group
  weights are clamped to Blender's [0, 1]; vertex marks (``ids.VERTEX_MARKS``)
  stay on the input vertices only;
* faces (material index, smooth/flat, custom): the value of the input face each
  output face lies in;
* edges (sharp, seam, crease, custom): the input edge's value on each of its r
  output segments, the default (0 / False) inside the faces.

Integer and boolean layers never blend: a corner or vertex takes the value of its
face's nearest corner (largest weight), which is the exact value at the input's own
elements.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import ids
from .attributes import Layer


@dataclass(frozen=True, eq=False)
class OutputLayer:
    """A carried layer on the output: ``values (n_out, width)`` for its domain."""

    name: str
    domain: str
    data_type: str
    values: np.ndarray
    group: bool = False


def _input_edges(tp, repair, edge_verts) -> np.ndarray:
    """(E',) the input edge (index into `edge_verts` (E, 2)) of each edge of the repaired
    topology `tp`, by its end vertices' weld representatives; -1 where there is none."""
    rep = np.asarray(repair.representative)
    V = len(rep)
    ev = np.sort(rep[np.asarray(edge_verts, dtype=np.int64).reshape(-1, 2)], axis=1)
    key = ev[:, 0] * V + ev[:, 1]
    if not len(key):
        return np.full(len(tp.edges), -1, dtype=np.int64)
    order = np.argsort(key, kind="stable")
    mine = np.sort(rep[np.asarray(repair.vertex_map)[tp.edges]], axis=1)
    want = mine[:, 0] * V + mine[:, 1]
    pos = np.minimum(np.searchsorted(key[order], want), len(key) - 1)
    return np.where(key[order][pos] == want, order[pos], -1)


def _floating(data_type: str) -> bool:
    return ids.CARRIED_TYPES[data_type][3] < 2


def input_corners(tp, repair, inp) -> np.ndarray:
    """(C',) the input CSR corner of each corner of the repaired topology `tp`: the corner
    of its input face (``repair.face_map``) at the same vertex (``repair.vertex_map``,
    compared through the vertices' weld representatives; a face cut into loops or
    reoriented keeps its corners' vertices). The first such corner where a face visits a
    vertex twice."""
    vmap, fmap = np.asarray(repair.vertex_map), np.asarray(repair.face_map)
    rep = np.asarray(repair.representative)
    cface = np.repeat(np.arange(tp.n_faces), tp.face_sizes)  # repaired face of each corner
    f = fmap[cface]
    want = rep[vmap[tp.face_vertices]]
    start, size = inp.offsets[f], np.diff(inp.offsets)[f]
    out = np.full(len(f), -1, dtype=np.int64)
    for j in range(int(size.max()) if len(size) else 0):
        c = np.minimum(start + j, len(inp.corners) - 1)
        hit = (out < 0) & (j < size) & (rep[inp.corners[c]] == want)
        out[hit] = c[hit]
    return np.where(out < 0, start, out)  # (unreachable for a repair's own faces)


class Transfer:
    """The maps from input elements to the elements of one output (built once per
    build, reused while only attribute values change).

    lattice: the output's ``Lattice`` (of the repaired mesh); quads: output quads in
    quad faces; values: ``apply(values (V, k)) -> (P, k)`` (the surface's linear map of
    the input's vertex values, a ``Stencil``); inp: the ``mesh_io.MeshInput`` built from
    (its Blender loops and edges); out_edges: number of output edges when their first
    E r are the mesh edges' segments (``Lattice.edges`` numbering), else None (edge
    layers not carried); repair: the surface's ``RepairedMesh`` (``vertex_map``,
    ``face_map``: a repaired mesh's output elements map back to the input's).
    """

    def __init__(self, lattice, quads: bool, values, inp, out_edges, repair):
        tp = lattice.topology
        vmap = np.asarray(repair.vertex_map)
        self.lattice, self.values = lattice, values
        self.offsets, self.corners, face, local = lattice.polygons(quads)
        self.face = np.asarray(repair.face_map)[face]  # the input face of each output face
        self.n_points = lattice.n_points
        # per face size, each as wide as its faces (a dense (corners, largest face) array
        # made a 100 x 100 grid with one 128-gon take 3.4 GB; a test with concave n-gons)
        cf = lattice.local_face[local]
        size = tp.face_sizes[cf]
        loops, source = inp.loops(), input_corners(tp, repair, inp)
        self._corner_groups = []  # (output corners, weights (k, n), input loops (k, n))
        self._corner_near = np.empty(len(local), dtype=np.int64)
        for n in np.unique(size).tolist():
            rows = np.flatnonzero(size == n)
            W = lattice.corner_weights(local=True, rows=local[rows])
            src = loops[source[tp.face_offsets[cf[rows]][:, None] + np.arange(n)]]
            self._corner_groups.append((rows, W, src))
            self._corner_near[rows] = src[np.arange(len(rows)), np.argmax(W, axis=1)]
        near = np.empty(lattice.n_points, dtype=np.int64)  # in each sample's evaluation face
        point_size = tp.face_sizes[lattice.face]
        for n in np.unique(point_size).tolist():
            rows = np.flatnonzero(point_size == n)
            near[rows] = np.argmax(lattice.corner_weights(rows=rows), axis=1)
        self._point_near = vmap[tp.face_vertices[tp.face_offsets[lattice.face] + near]]
        self.vertex_map = vmap  # the input vertex of each output vertex sample
        self.out_edges = out_edges
        self._edge_src = None
        if out_edges is not None:
            self._edge_src = np.repeat(_input_edges(tp, repair, inp.carried.edge_verts),
                                       lattice.resolution)  # input edge of each segment, or -1

    @property
    def n_corners(self) -> int:
        return len(self.corners)

    @property
    def n_faces(self) -> int:
        return len(self.face)

    def layer(self, layer: Layer) -> OutputLayer | None:
        """`layer` on the output (None: an edge layer without an edge map)."""
        v = layer.values
        if layer.domain == "CORNER":
            if _floating(layer.data_type):
                out = np.empty((len(self._corner_near),) + v.shape[1:])
                for rows, W, src in self._corner_groups:
                    out[rows] = np.einsum("ck,ck...->c...", W, v[src].astype(np.float64))
            else:
                out = v[self._corner_near]
        elif layer.domain == "FACE":
            out = v[self.face]
        elif layer.domain == "EDGE":
            if self._edge_src is None:
                return None
            out = np.zeros((self.out_edges,) + v.shape[1:], dtype=v.dtype)
            hit = self._edge_src >= 0
            out[:len(hit)][hit] = v[self._edge_src[hit]]
        elif layer.name in ids.VERTEX_MARKS and not layer.group:
            out = np.zeros((self.n_points,) + v.shape[1:], dtype=v.dtype)
            out[:len(self.vertex_map)] = v[self.vertex_map]
        elif _floating(layer.data_type):
            out = self.values.apply(v.astype(np.float64))
            if layer.group or layer.data_type == "BYTE_COLOR":
                np.clip(out, 0.0, 1.0, out=out)
        else:
            out = v[self._point_near]
        dtype = ids.CARRIED_TYPES[layer.data_type][2]
        return OutputLayer(layer.name, layer.domain, layer.data_type,
                           np.ascontiguousarray(out, dtype=dtype), layer.group)
