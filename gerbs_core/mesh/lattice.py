"""Crack-free sample lattices on polygon meshes (docs/design.md, stage 9 "Tessellation").

At resolution r (segments per edge) every face is sampled by a lattice:
triangles by the barycentric lattice {(i, j) / r}, quads by the r x r
bilinear lattice, n-gons (n >= 5) by a fan of n triangular lattices from the
face centre. Samples on mesh vertices and edges are shared by all incident
faces and stored ONCE, so no output point is duplicated and there are no
cracks: an edge sample is at the same fraction t of the edge from either side
(linear along straight edges in every reference polygon).

Global sample numbering (P samples):
    [0, V)                       mesh vertices (``vertex_sample = arange(V)``)
    [V, V + E(r-1))              edge interiors: ``edge_samples[e, m-1]`` at
                                 fraction m/r from ``edges[e,0]`` to ``edges[e,1]``
    then one block per face      face interiors (n-gons: centre, spokes, fan interiors)

Per-sample parameters (the face used to evaluate it, ``face[p]``):
    triangle  ``fan = -1``, ``uv = (l1, l2)``: barycentric w.r.t. corners 1, 2 (l0 = 1 - l1 - l2)
    quad      ``fan = -1``, ``uv = (s, t)``: bilinear, (1-s)(1-t) c0 + s(1-t) c1 + st c2 + (1-s)t c3
    n-gon     ``fan = k``,  ``uv = (l1, l2)`` in the fan triangle (centre, corner k, corner k+1)
A vertex sample is evaluated in the first face of its (ordered) star, an edge
sample in the face of the edge's first half-edge (``edge_halfedges[e, 0]``).

The local table (``local_*``) lists every (face, lattice point) occurrence,
sorted by face, with its parameters in that face and its global sample; it
lets callers (and tests) evaluate a shared sample from every incident face.

The per-face-size templates are :mod:`.lattice_templates`; the output mesh's faces and
edges :mod:`.lattice_faces`; the map of samples into the polygons :mod:`.polygon_map`.
"""
from __future__ import annotations

from functools import cached_property
from typing import NamedTuple

import numpy as np

from ..errors import InvalidParameterError, ResourceLimitError
from ..immutable import ReadOnlyArrays
from ..inputs import integer
from .arrays import read_only as _ro
from .lattice_faces import output_edges, polygon_table
from .lattice_templates import (CORNER, EDGE, INTERIOR, face_counts, template, template_tris,
                                variant_rows)
from .polygon_map import corner_weights, map_to_polygon

__all__ = ["Lattice", "SizeClass", "output_counts"]


def _check_resolution(r) -> int:
    return integer("resolution", r, 1, " (segments per edge)")


def output_counts(topology, resolution: int) -> tuple[int, int]:
    """Exact (points, triangles) of :class:`Lattice` ``(topology, resolution)``.

    points    = V + E (r-1) + sum_tri (r-1)(r-2)/2 + sum_quad (r-1)^2
                + sum_ngon [1 + n (r-1) + n (r-1)(r-2)/2]
    triangles = sum_tri r^2 + sum_quad 2 r^2 + sum_ngon n r^2
    """
    r = _check_resolution(resolution)
    sizes = np.asarray(topology.face_sizes)
    n3, n4 = int((sizes == 3).sum()), int((sizes == 4).sum())
    ng, sg = int((sizes >= 5).sum()), int(sizes[sizes >= 5].sum())
    nt = (r - 1) * (r - 2) // 2  # Python ints: no overflow for absurd resolutions
    pts = (int(topology.n_vertices) + int(topology.n_edges) * (r - 1) + n3 * nt
           + n4 * (r - 1) ** 2 + ng + sg * (r - 1) + sg * nt)
    return pts, r * r * (n3 + 2 * n4 + sg)


def _scatter_rows(dst: np.ndarray, rows: np.ndarray, src: np.ndarray) -> None:
    """dst[rows] = src for C-contiguous 2-D arrays, each row moved as one opaque item
    (numpy's row-wise fancy assignment is ~2x slower for short rows)."""
    item = np.dtype((np.void, dst.itemsize * dst.shape[1]))
    dst.view(item).ravel()[rows] = np.ascontiguousarray(src, dtype=dst.dtype).view(item).ravel()


class SizeClass(NamedTuple):
    """The faces with n corners and the global samples of their template points."""

    faces: np.ndarray    # (nf,) the faces, ascending
    samples: np.ndarray  # (nf, npt) global sample of every template point of every face
    owned: np.ndarray    # (nf, npt) bool: the occurrence that evaluates its sample
    n: int


def _size_class(tp, r: int, n: int, block, owner_corner, first_he) -> SizeClass:
    """The samples of the faces with n corners: mesh vertices, the edge samples counted
    from ``edges[e,0]`` (reversed where the face runs the edge backwards) and the face
    interiors from ``block`` (F,). A shared sample is owned by the face of its vertex's
    first star corner or its edge's first half-edge."""
    fo, fv, V = tp.face_offsets, tp.face_vertices, tp.n_vertices
    fk = np.flatnonzero(tp.face_sizes == n)
    uv, fan, kind, loc, pos, canon, tris = template(n, r)
    nf, npt = len(fk), len(kind)
    base = fo[fk][:, None]
    G = np.empty((nf, npt), dtype=np.int64)
    own = np.zeros((nf, npt), dtype=bool)
    c = kind == CORNER
    h = base + loc[c]
    G[:, c] = fv[h]
    own[:, c] = canon[c] & (h == owner_corner[fv[h]])
    c = kind == EDGE
    h = base + loc[c]
    e = tp.halfedge_edge[h]
    fwd = fv[h] == tp.edges[e, 0]
    G[:, c] = V + e * (r - 1) + np.where(fwd, pos[c] - 1, r - 1 - pos[c])
    own[:, c] = canon[c] & (h == first_he[e])
    c = kind == INTERIOR
    G[:, c] = block[fk][:, None] + loc[c]
    own[:, c] = canon[c]
    return SizeClass(fk, G, own, n)


def _face_tables(classes, F: int):
    """(local_sample (L,), local_offsets (F+1,)) in face order.

    The per-class tables are merged by offsets (each face is in exactly one class, in
    template order): scatters, no sort."""
    npts = np.zeros(F, dtype=np.int64)
    for fk, G, _, _ in classes:
        npts[fk] = G.shape[1]
    loff = np.zeros(F + 1, dtype=np.int64)
    np.cumsum(npts, out=loff[1:])
    local_sample = np.empty(int(loff[-1]), dtype=np.int64)
    for fk, G, own, n in classes:
        npt = G.shape[1]
        if len(classes) == 1:
            local_sample[:] = G.ravel()
        else:
            local_sample[(loff[fk][:, None] + np.arange(npt)).ravel()] = G.ravel()
    return local_sample, loff


def _face_triangles(classes, F: int, tcount, T: int, r: int, flip: np.ndarray):
    """triangles (T, 3) in face order (merged by offsets like :func:`_face_tables`); a
    class's faces of another triangulation (``flip`` (F,), the variant of
    :func:`template_tris`) overwrite its block."""
    toff = np.zeros(F + 1, dtype=np.int64)
    np.cumsum(tcount, out=toff[1:])
    tri = np.empty((T, 3), dtype=np.int64)
    for fk, G, own, n in classes:
        for rows, v in variant_rows(flip[fk]):
            tris = template_tris(n, r, v)
            if len(classes) == 1 and isinstance(rows, slice):
                tri[:] = G[:, tris].reshape(-1, 3)
            else:
                dest = (toff[fk[rows]][:, None] + np.arange(len(tris))).ravel()
                _scatter_rows(tri, dest, G[rows][:, tris].reshape(-1, 3))
    return tri


def _check_flip(flip, sizes) -> np.ndarray:
    """(F,) int64 read-only variants: -1 everywhere (None) or ``flip`` checked (a triangle's
    corner 0..2 or -1; -1 for every other face)."""
    if flip is None:
        return _ro(np.full(len(sizes), -1, dtype=np.int64))
    f = np.asarray(flip)
    if f.shape != (len(sizes),) or f.dtype.kind not in "iu" or (f < -1).any() \
            or (f > np.where(sizes == 3, 2, -1)).any():
        raise InvalidParameterError("flip", f"must be (F,) = ({len(sizes)},) integers: a "
                                    f"triangle's obtuse corner 0..2 or -1")
    return _ro(f.astype(np.int64))


class Lattice(ReadOnlyArrays):
    """Samples and output triangles of ``topology`` at ``resolution`` r >= 1 (immutable).

    Attributes (read-only arrays; P samples, T triangles, L local entries):
      ``n_points``, ``n_triangles``, ``resolution``, ``topology``
      ``face (P,)``, ``fan (P,)``, ``uv (P,2)``: evaluation face and parameters of each sample
      ``vertex_sample (V,)``: sample of each mesh vertex (= arange(V))
      ``edge_samples (E, r-1)``: interior samples of edge e from ``edges[e,0]`` to ``edges[e,1]``
      ``triangles (T,3)``: output triangles (made on first use), oriented like their faces, grouped by face
      ``triangle_face (T,)``: the face each output triangle lies in
      ``local_face, local_fan, local_uv, local_sample (L,)``: every lattice point of every
      face (shared points once per incident face), sorted by face, CSR ``local_offsets (F+1,)``
      ``size_classes``: a :class:`SizeClass` per face size, ascending
      ``flip (F,)``: each face's triangulation: -1 the lattice's own, k = 0..2 (triangles)
      :func:`~.lattice_templates.flipped_triangles` for an obtuse corner k (the same
      samples; only the triangles, :meth:`polygons` and :meth:`edges` inside the face differ)

    ``max_points``: refuse (ResourceLimitError, stating the estimate) if P would exceed it.
    ``flip``: (F,) the variants (default all -1; :func:`~.lattice_templates.obtuse_flips`).
    """

    def __init__(self, topology, resolution: int, max_points: int | None = None,
                 flip=None):
        r = _check_resolution(resolution)
        P, T = output_counts(topology, r)
        if max_points is not None and P > max_points:
            raise ResourceLimitError(f"resolution {r} gives {P} points and {T} triangles, more "
                                     f"than max_points={max_points}")
        tp = topology
        V, E, F = tp.n_vertices, tp.n_edges, tp.n_faces
        self.flip = _check_flip(flip, np.asarray(tp.face_sizes))
        inner, tcount = face_counts(tp.face_sizes, r)
        block = V + E * (r - 1) + np.concatenate([[0], np.cumsum(inner)[:-1]])
        owner_corner = tp.star_corners[tp.star_offsets[:-1]]
        classes = tuple(_size_class(tp, r, n, block, owner_corner, tp.edge_halfedges[:, 0])
                        for n in np.unique(tp.face_sizes).tolist())
        face_g = np.empty(P, dtype=np.int64)
        for fk, G, own, _ in classes:
            face_g[G[own]] = np.broadcast_to(fk[:, None], G.shape)[own]
        local_sample, loff = _face_tables(classes, F)
        self.size_classes = classes
        self.local_sample = _ro(local_sample)
        self.local_offsets = _ro(loff)
        self._tcount = tcount
        self.face = _ro(face_g)
        self.vertex_sample = _ro(np.arange(V, dtype=np.int64))
        self.edge_samples = _ro(V + np.arange(E * (r - 1), dtype=np.int64).reshape(E, r - 1))
        self.topology, self.resolution = tp, r
        self.n_points, self.n_triangles = P, T

    def __repr__(self) -> str:
        return (f"Lattice(resolution={self.resolution}, n_points={self.n_points}, "
                f"n_triangles={self.n_triangles}, faces={self.topology.n_faces})")

    @cached_property
    def triangles(self) -> np.ndarray:
        """(T, 3) the output triangles (made on first use: 24 bytes a triangle, which a
        stencil's assembly and W @ X never read)."""
        return _ro(_face_triangles(self.size_classes, self.topology.n_faces, self._tcount,
                                   self.n_triangles, self.resolution, self.flip))

    # faces in face order: made on first use from the counts
    @cached_property
    def triangle_face(self) -> np.ndarray:
        return _ro(np.repeat(np.arange(self.topology.n_faces, dtype=np.int64), self._tcount))

    @cached_property
    def local_face(self) -> np.ndarray:
        return _ro(np.repeat(np.arange(self.topology.n_faces, dtype=np.int64),
                             np.diff(self.local_offsets)))

    # per-sample and local-table parameters are made on first use (callers that need only
    # the connectivity never build them); each pair is built together
    @property
    def uv(self) -> np.ndarray:
        return self._sample_params[0]

    @property
    def fan(self) -> np.ndarray:
        return self._sample_params[1]

    @property
    def local_uv(self) -> np.ndarray:
        return self._local_params[0]

    @property
    def local_fan(self) -> np.ndarray:
        return self._local_params[1]

    @cached_property
    def _sample_params(self):
        """(uv (P, 2), fan (P,)) of every output sample (cached: :attr:`uv`, :attr:`fan`)."""
        return self.sample_params()

    def sample_params(self):
        """(uv (P, 2), fan (P,)) of every output sample, the cached ones if made, else made
        anew and not kept (24 bytes a sample: a stencil's assembly needs them once, and a
        stencil keeps its lattice)."""
        if "_sample_params" in self.__dict__:
            return self.__dict__["_sample_params"]
        uv_g = np.empty((self.n_points, 2))
        fan_g = np.empty(self.n_points, dtype=np.int64)
        for fk, G, own, n in self.size_classes:
            uv, fan = template(n, self.resolution)[:2]
            sel = G[own]
            fan_g[sel] = np.broadcast_to(fan, G.shape)[own]
            uv_g[sel] = np.broadcast_to(uv, G.shape + (2,))[own]
        return _ro(uv_g), _ro(fan_g)

    @cached_property
    def _local_params(self):
        """(local_uv (L, 2), local_fan (L,)) of every lattice point of every face."""
        L = len(self.local_face)
        uv_l = np.empty((L, 2))
        fan_l = np.empty(L, dtype=np.int64)
        lo = self.local_offsets
        for fk, G, own, n in self.size_classes:
            uv, fan = template(n, self.resolution)[:2]
            dest = (lo[fk][:, None] + np.arange(G.shape[1])).ravel()
            uv_l[dest] = np.tile(uv, (len(fk), 1))
            fan_l[dest] = np.tile(fan, len(fk))
        return _ro(uv_l), _ro(fan_l)

    def polygons(self, quads: bool = True):
        """The output faces: quads in quad faces (with `quads`), triangles elsewhere.

        Returns read-only (offsets (Fo+1,), corners (Co,), face (Fo,), local (Co,)) int64:
        output face o has the samples ``corners[offsets[o]:offsets[o+1]]`` (oriented
        like its face, grouped by face in face order; with ``quads=False`` exactly
        :attr:`triangles`), lies in mesh face ``face[o]``, and its corner c is the
        entry ``local[c]`` of the local table (``local_sample[local[c]] ==
        corners[c]``), whose parameters in that face interpolate per-corner values
        (``corner_weights(local=True)[local]``): exact at the mesh's face corners.
        """
        key = bool(quads)
        cache = self.__dict__.setdefault("_polygon_tables", {})
        if key not in cache:
            cache[key] = polygon_table(self, key)
        return cache[key]

    def edges(self, quads: bool = False):
        """(edge_verts (E_out, 2), corner_edges) int32 of the output mesh, from the lattice
        structure (no hashing of its half-edges), or None where that structure alone does
        not settle it (triangulated quads at resolution 1: two quads may share a diagonal).

        quads=False: the output triangles, ``corner_edges (T, 3)``; quads=True: the
        faces of :meth:`polygons` (quads in quad faces), ``corner_edges (Co,)``.

        Numbering: the r segments of every mesh edge e first (e*r + j, segment j
        from ``edges[e,0]``), then the edges inside the faces, face-size class by
        class, face by face. ``corner_edges[c]`` is the edge from corner c to the next
        corner of its output face (Blender's corner_edge convention). Every undirected
        edge of the output faces exactly once (tested against a hash).

        Why no hashing is needed: an edge inside a face joins two lattice points of
        that face; it can be another face's edge too only if both points lie on
        both faces, i.e. (r >= 2) on two sides meeting at a vertex w that both faces
        contain, so the two faces share both edges at w: w is an interior vertex of
        valence 2. Only the faces around such vertices are checked for repeats.
        """
        return output_edges(self, quads)

    def face_groups(self) -> tuple[np.ndarray, np.ndarray]:
        """(order (P,), offsets (F+1,)): ``order[offsets[f]:offsets[f+1]]`` are the samples
        evaluated in face f (``face[p] == f``), for per-face batched evaluation."""
        order = np.argsort(self.face, kind="stable")
        off = np.zeros(self.topology.n_faces + 1, dtype=np.int64)
        np.cumsum(np.bincount(self.face, minlength=self.topology.n_faces), out=off[1:])
        return order, off

    def corner_weights(self, local: bool = False, rows=None) -> np.ndarray:
        """(P, n_max) weights of each sample's face corners (slot k = corner k of its face,
        0 beyond the face size): sum_k w_k X_k is :meth:`map_to_polygon` of per-corner
        values X (n-gon centres the corners' mean), as a linear map. `rows` (int array):
        those samples only, (len(rows), their largest face size) -- one large n-gon makes
        the full array as wide for every sample."""
        return corner_weights(self, local, rows)

    def map_to_polygon(self, corners2d, centers=None, local: bool = False) -> np.ndarray:
        """Map samples into their faces' reference polygons (vectorized).

        corners2d : (C, d) coordinates of every corner, aligned with
            ``topology.face_vertices`` (d = 2 for reference polygons; any d works,
            e.g. ``X[topology.face_vertices]`` for the piecewise-linear mesh in 3D).
        centers : optional (F, d) fan centres of the n-gons (default: the mean of
            their corners, inside every convex polygon).
        local : map the local table (``local_face``, ...) instead of the samples.
        Returns (P, d) (or (L, d)): triangles barycentric, quads bilinear, n-gons
        barycentric in the fan triangle. Exact (affine/bilinear formulas).
        """
        return map_to_polygon(self, corners2d, centers, local)
