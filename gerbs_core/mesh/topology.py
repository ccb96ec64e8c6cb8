"""Polygon-mesh connectivity: CSR faces, edges, half-edges, ordered vertex stars.

:class:`MeshTopology` is built from faces alone (a list of int sequences or an
(F,k) int array; triangles, quads, n-gons, mixed; boundaries allowed) and is
immutable. It validates the mesh as an oriented 2-manifold with boundary and
raises :class:`~gerbs_core.errors.InvalidMeshError` otherwise (problem tags
below). :class:`~gerbs_core.mesh.surface.BlendingSurface` repairs all of them except
``bad_shape``, ``empty`` and ``index_out_of_range`` first (:mod:`gerbs_core.mesh.repair`). :func:`gerbs_core.mesh.validation.validate_geometry` checks vertex
positions against a topology.

Conventions (all arrays int64, read-only):

* corners: ``face_vertices[face_offsets[f]:face_offsets[f+1]]`` are the
  vertices of face f in order; corner c belongs to face ``corner_face[c]``.
* half-edges are indexed like corners: half-edge c runs from
  ``face_vertices[c]`` to ``face_vertices[corner_next[c]]``; ``halfedge_twin[c]``
  is the opposite half-edge or -1 on the boundary.
* edges: ``edges (E,2)`` with ``edges[e,0] < edges[e,1]``, sorted
  lexicographically; ``halfedge_edge (C,)``; ``edge_halfedges (E,2)`` (second
  column -1 for a boundary edge); ``edge_faces (E,2)`` likewise.
* stars: ``star_corners[star_offsets[v]:star_offsets[v+1]]`` are the corners
  at v ordered counter-clockwise (the sense of the face orientation). For a
  boundary vertex the open fan starts at the face whose outgoing half-edge
  (v -> next) is a boundary edge and ends at the face whose incoming
  half-edge is a boundary edge. ``ring_vertices`` (CSR ``ring_offsets``) is the
  1-ring in the same order (boundary vertices: one more neighbour than faces).

Problem tags of the topological validation, checked in this order (the first
failing check raises, naming all its offending elements):

``bad_shape``      faces not a sequence of int sequences / (F,k) int array
``empty``          no faces or no vertices
``index_out_of_range``  a face refers to a vertex outside [0, n_vertices) (element face)
``degenerate_face``     a face with fewer than 3 distinct vertices (element face)
``repeated_index``      a face visiting a vertex twice, >= 3 distinct (element face)
``duplicate_face``      two faces with the same vertex set (element face, all copies)
``non_manifold_edge``   an edge used by more than two faces (element vertex: the
                        edges' end points; ``err.edges`` holds the pairs, ``err.faces`` the faces)
``inconsistent_orientation``  an edge traversed in the same direction by its two
                        faces: flipped normals or a non-orientable mesh (element
                        vertex, with ``err.edges``/``err.faces`` as above)
``non_manifold_vertex`` a vertex whose faces form more than one fan (bow-tie) (element vertex)
``unused_vertex``       a vertex in no face (element vertex). Checked first after the
                        range check when there are more vertices than corners (then
                        at most the first C + 1000 indices are examined), so that a
                        huge ``n_vertices`` never allocates O(V) memory.
"""
from __future__ import annotations

import itertools
from functools import cached_property

import numpy as np

from ..errors import InvalidMeshError
from ..immutable import ReadOnlyArrays
from ..inputs import check_index, is_integer
from .arrays import read_only as _ro
from .topology_build import check_faces, check_indices, face_cycles, mesh_edges, vertex_stars

__all__ = ["MeshTopology"]


def _parse_faces(faces, n_vertices):
    """Faces -> (sizes (F,), flat (C,)) int64, or raise bad_shape / empty."""
    if isinstance(faces, np.ndarray) and faces.dtype != object:
        if faces.size == 0:
            raise InvalidMeshError("empty", "empty: the mesh has no faces", None, "face")
        if faces.ndim != 2:
            raise InvalidMeshError("bad_shape", f"bad_shape: a face array must be (F, k), got "
                                   f"shape {faces.shape}", None, "face")
        if faces.dtype.kind not in "iu":
            raise InvalidMeshError("bad_shape", f"bad_shape: face indices must be integers, got "
                                   f"dtype {faces.dtype}", None, "face")
        flat = faces.astype(np.int64).ravel()  # a copy: the caller's array is never touched
        sizes = np.full(faces.shape[0], faces.shape[1], dtype=np.int64)
    else:
        try:
            faces = list(faces)
        except TypeError:
            raise InvalidMeshError("bad_shape", f"bad_shape: faces must be a sequence of int "
                                   f"sequences, got {type(faces).__name__}", None, "face") from None
        if not faces:
            raise InvalidMeshError("empty", "empty: the mesh has no faces", None, "face")
        try:
            sizes = np.fromiter(map(len, faces), dtype=np.int64, count=len(faces))
        except TypeError:
            bad = [i for i, f in enumerate(faces) if not hasattr(f, "__len__")]
            raise InvalidMeshError("bad_shape", "bad_shape: faces must be sequences of vertex "
                                   "indices; not a sequence:", bad, "face") from None
        try:
            flat = np.array(list(itertools.chain.from_iterable(faces)))
        except (TypeError, ValueError, OverflowError):
            flat = np.array([], dtype=object)
        if flat.size and flat.dtype.kind not in "iu" or (flat.size == 0 and sizes.sum() > 0):
            bad = [i for i, f in enumerate(faces)
                   if not all(isinstance(x, (int, np.integer)) and not isinstance(x, bool)
                              and -2**62 < x < 2**62 for x in f)]
            raise InvalidMeshError("bad_shape", "bad_shape: face entries must be integers; "
                                   "faces", bad, "face")
        flat = flat.astype(np.int64)
    if n_vertices == 0:
        raise InvalidMeshError("empty", "empty: the mesh has no vertices", None, "vertex")
    return sizes, flat


class MeshTopology(ReadOnlyArrays):
    """Immutable connectivity of an oriented polygon 2-manifold with boundary.

    Parameters
    ----------
    faces : sequence of int sequences, or (F, k) int array
        Vertex indices of each face, in a consistent orientation.
    n_vertices : int, optional
        Number of vertices (default: max index + 1). Every vertex must be used.

    Raises :class:`InvalidMeshError` (see the module docstring for the tags).
    Construction is vectorized (:mod:`.topology_build`): O(C log C) for C corners.
    """

    def __init__(self, faces, n_vertices: int | None = None):
        if n_vertices is not None:
            if not is_integer(n_vertices) or n_vertices < 0:
                raise InvalidMeshError("bad_shape", f"bad_shape: n_vertices must be an integer "
                                       f">= 0, got {n_vertices!r}", None, "vertex")
        self._build(*_parse_faces(faces, n_vertices), n_vertices)

    @classmethod
    def from_csr(cls, sizes, flat, n_vertices: int) -> "MeshTopology":
        """The topology of faces given as CSR: ``sizes (F,)`` corner counts and ``flat (C,)``
        vertex of each corner (int64), with the same checks as the constructor (no
        Python-list round trip; used by :mod:`gerbs_core.mesh.repair`)."""
        topo = cls.__new__(cls)
        sizes, flat = np.asarray(sizes, dtype=np.int64), np.asarray(flat, dtype=np.int64)
        if not len(sizes) or not int(n_vertices):
            raise InvalidMeshError("empty", "empty: the mesh has no faces", None, "face")
        topo._build(sizes, flat.copy(), int(n_vertices))
        return topo

    def _build(self, sizes, flat, n_vertices):
        """Validate the CSR faces (in the order of the module docstring's tags) and set
        every array (:mod:`.topology_build`)."""
        V = int(flat.max(initial=-1)) + 1 if n_vertices is None else int(n_vertices)
        if n_vertices is None and V <= 0:
            V = 1  # all indices negative: reported as out of range
        F, C = len(sizes), len(flat)
        offsets = np.zeros(F + 1, dtype=np.int64)
        np.cumsum(sizes, out=offsets[1:])
        cface = np.repeat(np.arange(F, dtype=np.int64), sizes)
        check_indices(flat, cface, V)
        check_faces(sizes, offsets, flat, cface)
        used = np.bincount(flat, minlength=V)
        nxt, prv = face_cycles(offsets)
        he_edge, e_he, twin, edges = mesh_edges(flat, nxt, cface, V)
        star_offsets, star_corners, vb = vertex_stars(flat, prv, twin, used, V)
        if (used == 0).any():
            raise InvalidMeshError("unused_vertex", "unused_vertex: vertices in no face",
                                   np.flatnonzero(used == 0), "vertex")
        self.n_vertices, self.n_faces, self.n_edges, self.n_corners = V, F, len(edges), C
        self.face_offsets = _ro(offsets)
        self.face_vertices = _ro(flat)
        self.face_sizes = _ro(sizes)
        self.corner_face = _ro(cface)
        self.corner_next = _ro(nxt)
        self.corner_prev = _ro(prv)
        self.halfedge_twin = _ro(twin)
        self.halfedge_edge = _ro(he_edge)
        self.edges = _ro(edges)
        self.edge_halfedges = _ro(e_he)
        self.edge_faces = _ro(np.where(e_he >= 0, cface[e_he], -1))
        self.edge_is_boundary = _ro(e_he[:, 1] < 0)
        self.vertex_is_boundary = _ro(vb)
        self.star_offsets = _ro(star_offsets)
        self.star_corners = _ro(star_corners)
        self._frozen = True

    def __setattr__(self, name, value):
        if getattr(self, "_frozen", False):
            raise AttributeError(f"MeshTopology is immutable (cannot set {name!r})")
        object.__setattr__(self, name, value)

    # ------------------------------------------------------------------ queries
    @cached_property
    def star_faces(self) -> np.ndarray:
        """(C,) face of each star corner (CSR ``star_offsets``), counter-clockwise."""
        return _ro(self.corner_face[self.star_corners])

    @cached_property
    def vertex_valence(self) -> np.ndarray:
        """(V,) number of edges at each vertex (= faces, +1 on the boundary)."""
        return _ro(np.diff(self.star_offsets) + self.vertex_is_boundary)

    @cached_property
    def _ring(self):
        V, so, sc = self.n_vertices, self.star_offsets, self.star_corners
        val = np.diff(so) + self.vertex_is_boundary
        ro = np.zeros(V + 1, dtype=np.int64)
        np.cumsum(val, out=ro[1:])
        rv = np.empty(ro[-1], dtype=np.int64)
        pos = np.repeat(ro[:-1] - so[:-1], np.diff(so)) + np.arange(len(sc))
        rv[pos] = self.face_vertices[self.corner_next[sc]]
        bv = np.flatnonzero(self.vertex_is_boundary)
        rv[ro[bv + 1] - 1] = self.face_vertices[self.corner_prev[sc[so[bv + 1] - 1]]]
        return _ro(ro), _ro(rv)

    @property
    def ring_offsets(self) -> np.ndarray:
        """(V+1,) CSR offsets of :attr:`ring_vertices`."""
        return self._ring[0]

    @property
    def ring_vertices(self) -> np.ndarray:
        """1-rings, counter-clockwise; entry i of vertex v's ring is the far end of the
        outgoing half-edge of its i-th star corner (boundary: plus the last neighbour)."""
        return self._ring[1]

    def star(self, v: int) -> np.ndarray:
        """Corners at vertex v, counter-clockwise (open fans from boundary to boundary)."""
        return self.star_corners[self.star_offsets[v]:self.star_offsets[v + 1]]

    def one_ring(self, v: int) -> np.ndarray:
        """Neighbours of v, counter-clockwise (see :attr:`ring_vertices`)."""
        v = check_index("v", v, self.n_vertices)
        return self.ring_vertices[self.ring_offsets[v]:self.ring_offsets[v + 1]]

    def face(self, f: int) -> np.ndarray:
        """Vertex indices of face f in order."""
        f = check_index("f", f, self.n_faces)
        return self.face_vertices[self.face_offsets[f]:self.face_offsets[f + 1]]

    def faces_as_list(self) -> list[tuple[int, ...]]:
        fv = self.face_vertices.tolist()
        o = self.face_offsets.tolist()
        return [tuple(fv[o[f]:o[f + 1]]) for f in range(self.n_faces)]

    def k_ring(self, v, k: int, include_self: bool = False) -> np.ndarray:
        """Sorted vertices at edge distance 1..k from v (or from a set of vertices v)."""
        ro, rv = self.ring_offsets, self.ring_vertices
        seen = np.zeros(self.n_vertices, dtype=bool)
        front = np.unique(np.atleast_1d(np.asarray(v, dtype=np.int64)))
        seen[front] = True
        for _ in range(int(k)):
            if not front.size:
                break
            idx = np.concatenate([np.arange(ro[u], ro[u + 1]) for u in front])
            nb = np.unique(rv[idx])
            front = nb[~seen[nb]]
            seen[front] = True
        if not include_self:
            seen[np.atleast_1d(v)] = False
        return np.flatnonzero(seen)

    @cached_property
    def _vertex_face_csr(self):
        """Sparse (V, F) incidence, for face-ring queries."""
        from scipy.sparse import csr_matrix
        C = self.n_corners
        return csr_matrix((np.ones(C, dtype=np.int8), (self.face_vertices, self.corner_face)),
                          shape=(self.n_vertices, self.n_faces))

    def face_k_ring(self, v, k: int = 1) -> np.ndarray:
        """Sorted faces within k face layers of vertex v (or a set of vertices).

        Layer 1 is the star of v; layer j+1 adds every face sharing a vertex
        with layer j (the "faces beyond the link").
        """
        M = self._vertex_face_csr
        verts = np.unique(np.atleast_1d(np.asarray(v, dtype=np.int64)))
        faces = np.zeros(0, dtype=np.int64)
        for _ in range(max(int(k), 0)):
            faces = np.unique(M[verts].indices)
            verts = np.unique(np.concatenate([self.face(f) for f in faces]))
        return faces.astype(np.int64)

    @cached_property
    def halfedge_twin_face(self) -> np.ndarray:
        """(C,) face on the other side of each half-edge, -1 on the boundary."""
        t = self.halfedge_twin
        return _ro(np.where(t >= 0, self.corner_face[np.maximum(t, 0)], -1))

    def face_neighbors(self, f: int) -> np.ndarray:
        """Faces across the edges of face f, in corner order (-1 for a boundary edge)."""
        return self.halfedge_twin_face[self.face_offsets[f]:self.face_offsets[f + 1]]

    @cached_property
    def face_adjacency(self):
        """scipy.sparse.csr_matrix (F, F): 1 where two faces share an edge."""
        from scipy.sparse import csr_matrix
        e = self.edge_faces[~self.edge_is_boundary]
        F = self.n_faces
        return csr_matrix((np.ones(2 * len(e), dtype=np.int8),
                           (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(F, F))

    @cached_property
    def boundary_loops(self) -> tuple[np.ndarray, ...]:
        """Boundary loops as vertex arrays, each following the half-edge direction
        (the mesh lies to the left), starting at its smallest half-edge index."""
        bh = np.flatnonzero(self.halfedge_twin < 0)
        if not bh.size:
            return ()
        fv = self.face_vertices
        out_of = np.full(self.n_vertices, -1, dtype=np.int64)
        out_of[fv[bh]] = bh
        nxt = out_of[fv[self.corner_next[bh]]]  # boundary half-edge leaving the end vertex
        nxt_map = dict(zip(bh.tolist(), nxt.tolist()))
        seen, loops = set(), []
        for h in bh.tolist():
            if h in seen:
                continue
            loop = []
            while h not in seen:
                seen.add(h)
                loop.append(h)
                h = nxt_map[h]
            loops.append(_ro(fv[np.asarray(loop, dtype=np.int64)]))
        return tuple(loops)

    @property
    def is_closed(self) -> bool:
        return not bool(self.edge_is_boundary.any())

    @property
    def euler_characteristic(self) -> int:
        return self.n_vertices - self.n_edges + self.n_faces

    def __repr__(self):
        return (f"MeshTopology(V={self.n_vertices}, E={self.n_edges}, F={self.n_faces}, "
                f"boundary_edges={int(self.edge_is_boundary.sum())})")
