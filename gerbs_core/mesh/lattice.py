"""Crack-free sample lattices on polygon meshes (DESIGN section 5, "Tessellation").

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
"""
from __future__ import annotations

from functools import cached_property, lru_cache

import numpy as np

from ..errors import InvalidParameterError, ResourceLimitError

__all__ = ["Lattice", "output_counts"]

_CORNER, _EDGE, _INTERIOR = 0, 1, 2


def _check_resolution(r) -> int:
    if isinstance(r, (bool, np.bool_)) or not isinstance(r, (int, np.integer)) or r < 1:
        raise InvalidParameterError("resolution", f"must be an integer >= 1 (segments per "
                                    f"edge), got {r!r}")
    return int(r)


def _face_counts(sizes: np.ndarray, r: int):
    """(interior samples, output triangles) per face of the given corner counts."""
    sizes = np.asarray(sizes, dtype=np.int64)
    nt = (r - 1) * (r - 2) // 2
    inner = np.where(sizes == 3, nt, np.where(sizes == 4, (r - 1) ** 2,
                                              1 + sizes * (r - 1) + sizes * nt))
    tris = np.where(sizes == 4, 2 * r * r, np.where(sizes == 3, r * r, sizes * r * r))
    return inner, tris


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


@lru_cache(maxsize=64)
def _template(n: int, r: int):
    """Lattice template of an n-gon at resolution r (read-only arrays).

    Returns (uv, fan, kind, loc, pos, canonical, tris): per lattice point its
    parameters and fan, its kind (corner/edge/interior), ``loc`` the corner or
    edge (k: corner k -> k+1) number or the interior number, ``pos`` = m, the
    position 1..r-1 along edge ``loc`` from corner k; ``canonical`` marks the
    one occurrence of each point of the face that may own it; ``tris`` the
    counter-clockwise lattice triangles in template indices.
    """
    ij = np.array([(i, j) for j in range(r + 1) for i in range(r + 1 - j)], dtype=np.int64)
    i, j = ij[:, 0], ij[:, 1]
    lut = np.full((r + 1, r + 1), -1, dtype=np.int64)
    lut[i, j] = np.arange(len(ij))
    # lattice triangles of the barycentric lattice: up (i,j),(i+1,j),(i,j+1); down ...
    up = ij[i + j < r]
    dn = ij[i + j < r - 1]
    tri_t = np.concatenate([
        np.stack([lut[up[:, 0], up[:, 1]], lut[up[:, 0] + 1, up[:, 1]], lut[up[:, 0], up[:, 1] + 1]], 1),
        np.stack([lut[dn[:, 0] + 1, dn[:, 1]], lut[dn[:, 0] + 1, dn[:, 1] + 1],
                  lut[dn[:, 0], dn[:, 1] + 1]], 1)])
    inner_t = (i >= 1) & (j >= 1) & (i + j < r)
    inum_t = np.cumsum(inner_t) - 1
    nt = (r - 1) * (r - 2) // 2
    m_ = len(ij)

    if n == 3:
        uv = ij / r
        kind = np.full(m_, _INTERIOR)
        loc, pos = inum_t.copy(), np.zeros(m_, dtype=np.int64)
        for (ci, cj), k in (((0, 0), 0), ((r, 0), 1), ((0, r), 2)):
            sel = (i == ci) & (j == cj)
            kind[sel], loc[sel] = _CORNER, k
        for sel, k, m in (((j == 0) & (i > 0) & (i < r), 0, i),
                          ((i + j == r) & (j > 0) & (j < r), 1, j),
                          ((i == 0) & (j > 0) & (j < r), 2, r - j)):
            kind[sel], loc[sel], pos[sel] = _EDGE, k, m[sel]
        fan = np.full(m_, -1)
        canon = np.ones(m_, dtype=bool)
        tris = tri_t
    elif n == 4:
        jj, ii = np.meshgrid(np.arange(r + 1), np.arange(r + 1), indexing="ij")
        i, j = ii.ravel(), jj.ravel()
        uv = np.stack([i, j], 1) / r
        m_ = len(i)
        kind = np.full(m_, _INTERIOR)
        loc = (j - 1) * (r - 1) + (i - 1)
        pos = np.zeros(m_, dtype=np.int64)
        for (ci, cj), k in (((0, 0), 0), ((r, 0), 1), ((r, r), 2), ((0, r), 3)):
            sel = (i == ci) & (j == cj)
            kind[sel], loc[sel] = _CORNER, k
        mid = lambda a: (a > 0) & (a < r)  # noqa: E731
        for sel, k, m in (((j == 0) & mid(i), 0, i), ((i == r) & mid(j), 1, j),
                          ((j == r) & mid(i), 2, r - i), ((i == 0) & mid(j), 3, r - j)):
            kind[sel], loc[sel], pos[sel] = _EDGE, k, m[sel]
        fan = np.full(m_, -1)
        canon = np.ones(m_, dtype=bool)
        cj, ci = np.meshgrid(np.arange(r), np.arange(r), indexing="ij")
        a = (cj * (r + 1) + ci).ravel()
        b, c, d = a + 1, a + r + 2, a + r + 1
        tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    else:
        # fan k: (l1, l2) = (i, j)/r weights of corners k and k+1, centre weight the rest
        k_ = np.repeat(np.arange(n), m_)
        i, j = np.tile(i, n), np.tile(j, n)
        uv = np.stack([i, j], 1) / r
        fan = k_
        kind = np.full(n * m_, _INTERIOR)
        loc = np.zeros(n * m_, dtype=np.int64)
        pos = np.zeros(n * m_, dtype=np.int64)
        canon = np.ones(n * m_, dtype=bool)
        centre = (i == 0) & (j == 0)
        canon[centre & (k_ > 0)] = False  # loc 0 = the centre
        sel = (i == r) & (j == 0)
        kind[sel], loc[sel] = _CORNER, k_[sel]
        sel = (i == 0) & (j == r)
        kind[sel], loc[sel], canon[sel] = _CORNER, (k_[sel] + 1) % n, False
        sel = (i + j == r) & (j > 0) & (j < r)
        kind[sel], loc[sel], pos[sel] = _EDGE, k_[sel], j[sel]
        sel = (j == 0) & (i > 0) & (i < r)  # spoke k
        loc[sel] = 1 + k_[sel] * (r - 1) + i[sel] - 1
        sel = (i == 0) & (j > 0) & (j < r)  # spoke k+1, owned by fan k+1
        loc[sel], canon[sel] = 1 + ((k_[sel] + 1) % n) * (r - 1) + j[sel] - 1, False
        sel = np.tile(inner_t, n)
        loc[sel] = 1 + n * (r - 1) + k_[sel] * nt + np.tile(inum_t, n)[sel]
        tris = (tri_t[None] + (np.arange(n) * m_)[:, None, None]).reshape(-1, 3)
    out = (uv.astype(np.float64), fan.astype(np.int64), kind.astype(np.int64),
           loc.astype(np.int64), pos.astype(np.int64), canon, tris.astype(np.int64))
    for a in out:
        a.flags.writeable = False
    return out


@lru_cache(maxsize=64)
def _template_faces(n: int, r: int, quads: bool = False) -> np.ndarray:
    """Output faces of an n-gon template in template indices (read-only (k, m) array):
    with `quads` a quad's r x r cells (m = 4; cell (i, j) -> (i+1, j) -> (i+1, j+1) ->
    (i, j+1), counter-clockwise like the face), else the lattice triangles (m = 3)."""
    tris = _template(n, r)[6]
    if not (quads and n == 4):
        return tris
    c = r * r  # the triangles of a quad are (a, b, c) for every cell, then (a, c, d)
    out = np.stack([tris[:c, 0], tris[:c, 1], tris[:c, 2], tris[c:, 2]], 1)
    out.flags.writeable = False
    return out


@lru_cache(maxsize=64)
def _template_edges(n: int, r: int, quads: bool = False):
    """Edges of the output faces of an n-gon template (:func:`_template_faces`; read-only).

    Returns (tedge (te, 2), face_edge (k, m), side (te,), seg (te,)): the distinct
    undirected edges in template indices (repeated template points, e.g. an n-gon's
    centre, merged), the edge from corner i to corner i+1 of every template
    face, and for edges along the polygon's side k (corner k -> k+1) side = k
    and seg = m, the segment from position m to m+1 counted from corner k; side =
    -1 for edges inside the polygon (these come first).
    """
    uv, fan, kind, loc, pos, canon, _ = _template(n, r)
    tris = _template_faces(n, r, quads)
    npt = len(kind)
    _, first, inv = np.unique(np.stack([kind, loc, pos], 1), axis=0, return_index=True,
                              return_inverse=True)
    cid = first[inv.ravel()]  # canonical template index of every occurrence
    a = cid[tris]
    b = cid[np.roll(tris, -1, axis=1)]
    ukey, tri_edge = np.unique(np.minimum(a, b) * npt + np.maximum(a, b), return_inverse=True)
    tedge = np.stack([ukey // npt, ukey % npt], 1)
    side = np.full(len(tedge), -1, dtype=np.int64)
    seg = np.zeros(len(tedge), dtype=np.int64)
    for k in range(n):
        sp = np.full(npt, -1, dtype=np.int64)  # position along side k, or -1
        sp[(kind == _CORNER) & (loc == k)] = 0
        sp[(kind == _CORNER) & (loc == (k + 1) % n)] = r
        on = (kind == _EDGE) & (loc == k)
        sp[on] = pos[on]
        pa, pb = sp[tedge[:, 0]], sp[tedge[:, 1]]
        on = (pa >= 0) & (pb >= 0) & (np.abs(pa - pb) == 1)
        side[on], seg[on] = k, np.minimum(pa, pb)[on]
    order = np.argsort(side >= 0, kind="stable")  # inner edges first
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    out = (tedge[order], rank[tri_edge].reshape(tris.shape), side[order], seg[order])
    for x in out:
        x.flags.writeable = False
    return out


def _scatter_rows(dst: np.ndarray, rows: np.ndarray, src: np.ndarray) -> None:
    """dst[rows] = src for C-contiguous 2-D arrays, each row moved as one opaque item
    (numpy's row-wise fancy assignment is ~2x slower for short rows)."""
    item = np.dtype((np.void, dst.itemsize * dst.shape[1]))
    dst.view(item).ravel()[rows] = np.ascontiguousarray(src, dtype=dst.dtype).view(item).ravel()


def _ro(a):
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


class Lattice:
    """Samples and output triangles of ``topology`` at ``resolution`` r >= 1 (immutable).

    Attributes (read-only arrays; P samples, T triangles, L local entries):
      ``n_points``, ``n_triangles``, ``resolution``, ``topology``
      ``face (P,)``, ``fan (P,)``, ``uv (P,2)``: evaluation face and parameters of each sample
      ``vertex_sample (V,)``: sample of each mesh vertex (= arange(V))
      ``edge_samples (E, r-1)``: interior samples of edge e from ``edges[e,0]`` to ``edges[e,1]``
      ``triangles (T,3)``: output triangles, oriented like their faces, grouped by face
      ``triangle_face (T,)``: the face each output triangle lies in
      ``local_face, local_fan, local_uv, local_sample (L,)``: every lattice point of every
      face (shared points once per incident face), sorted by face, CSR ``local_offsets (F+1,)``

    ``max_points``: refuse (ResourceLimitError, stating the estimate) if P would exceed it.
    """

    def __init__(self, topology, resolution: int, max_points: int | None = None):
        r = _check_resolution(resolution)
        P, T = output_counts(topology, r)
        if max_points is not None and P > max_points:
            raise ResourceLimitError(f"resolution {r} gives {P} points and {T} triangles, more "
                                     f"than max_points={max_points}")
        tp = topology
        V, E, F = tp.n_vertices, tp.n_edges, tp.n_faces
        fo, fv, sizes = tp.face_offsets, tp.face_vertices, tp.face_sizes
        inner, tcount = _face_counts(sizes, r)
        block = V + E * (r - 1) + np.concatenate([[0], np.cumsum(inner)[:-1]])
        owner_corner = tp.star_corners[tp.star_offsets[:-1]]
        first_he = tp.edge_halfedges[:, 0]

        face_g = np.empty(P, dtype=np.int64)
        parts = []  # (faces, G (nf, npt) samples, own (nf, npt) owned, face size)
        for n in np.unique(sizes).tolist():
            fk = np.flatnonzero(sizes == n)
            uv, fan, kind, loc, pos, canon, tris = _template(n, r)
            nf, npt = len(fk), len(kind)
            base = fo[fk][:, None]
            G = np.empty((nf, npt), dtype=np.int64)
            own = np.zeros((nf, npt), dtype=bool)
            c = kind == _CORNER
            h = base + loc[c]
            G[:, c] = fv[h]
            own[:, c] = canon[c] & (h == owner_corner[fv[h]])
            c = kind == _EDGE
            h = base + loc[c]
            e = tp.halfedge_edge[h]
            fwd = fv[h] == tp.edges[e, 0]
            G[:, c] = V + e * (r - 1) + np.where(fwd, pos[c] - 1, r - 1 - pos[c])
            own[:, c] = canon[c] & (h == first_he[e])
            c = kind == _INTERIOR
            G[:, c] = block[fk][:, None] + loc[c]
            own[:, c] = canon[c]
            face_g[G[own]] = np.broadcast_to(fk[:, None], G.shape)[own]
            parts.append((fk, G, own, n))
        # the per-class tables are merged into face order by offsets (each face is in
        # exactly one class, in template order): scatters, no sort
        npts = np.zeros(F, dtype=np.int64)
        for fk, G, _, _ in parts:
            npts[fk] = G.shape[1]
        loff = np.zeros(F + 1, dtype=np.int64)
        np.cumsum(npts, out=loff[1:])
        toff = np.zeros(F + 1, dtype=np.int64)
        np.cumsum(tcount, out=toff[1:])
        local_sample = np.empty(int(loff[-1]), dtype=np.int64)
        tri = np.empty((T, 3), dtype=np.int64)
        for fk, G, own, n in parts:
            tris = _template(n, r)[6]
            npt, nt_ = G.shape[1], len(tris)
            if len(parts) == 1:
                local_sample[:] = G.ravel()
                tri[:] = G[:, tris].reshape(-1, 3)
            else:
                local_sample[(loff[fk][:, None] + np.arange(npt)).ravel()] = G.ravel()
                dest = (toff[fk][:, None] + np.arange(nt_)).ravel()
                _scatter_rows(tri, dest, G[:, tris].reshape(-1, 3))
        self._parts = parts
        self.local_sample = _ro(local_sample)
        self.local_offsets = _ro(loff)
        self.triangles = _ro(tri)
        self._tcount = tcount
        self.face = _ro(face_g)
        self.vertex_sample = _ro(np.arange(V, dtype=np.int64))
        self.edge_samples = _ro(V + np.arange(E * (r - 1), dtype=np.int64).reshape(E, r - 1))
        self.topology, self.resolution = tp, r
        self.n_points, self.n_triangles = P, T
        assert len(self.triangles) == T and int(tcount.sum()) == T

    # faces in face order: made on first use from the counts
    @cached_property
    def triangle_face(self) -> np.ndarray:
        return _ro(np.repeat(np.arange(self.topology.n_faces, dtype=np.int64), self._tcount))

    @cached_property
    def local_face(self) -> np.ndarray:
        return _ro(np.repeat(np.arange(self.topology.n_faces, dtype=np.int64),
                             np.diff(self.local_offsets)))

    # per-sample and local-table parameters are made on first use (the stencil of a
    # mode "regular" surface needs neither); each pair is built together
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
        """(uv (P, 2), fan (P,)) of every output sample."""
        uv_g = np.empty((self.n_points, 2))
        fan_g = np.empty(self.n_points, dtype=np.int64)
        for fk, G, own, n in self._parts:
            uv, fan = _template(n, self.resolution)[:2]
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
        for fk, G, own, n in self._parts:
            uv, fan = _template(n, self.resolution)[:2]
            dest = (lo[fk][:, None] + np.arange(G.shape[1])).ravel()
            uv_l[dest] = np.tile(uv, (len(fk), 1))
            fan_l[dest] = np.tile(fan, len(fk))
        return _ro(uv_l), _ro(fan_l)

    def _corner_counts(self, quads: bool) -> np.ndarray:
        """(F,) output corners of each face: 4 r^2 for quads with `quads`, else 3 x its
        triangles."""
        sizes, r = self.topology.face_sizes, self.resolution
        return np.where((sizes == 4) & quads, 4 * r * r, 3 * _face_counts(sizes, r)[1])

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
            cache[key] = self._polygon_table(key)
        return cache[key]

    def _polygon_table(self, quads: bool):
        tp, r = self.topology, self.resolution
        ccount = self._corner_counts(quads)
        coff = np.zeros(tp.n_faces + 1, dtype=np.int64)
        np.cumsum(ccount, out=coff[1:])
        fcount = np.where((tp.face_sizes == 4) & quads, r * r, _face_counts(tp.face_sizes, r)[1])
        foff = np.zeros(tp.n_faces + 1, dtype=np.int64)
        np.cumsum(fcount, out=foff[1:])
        corners = np.empty(int(coff[-1]), dtype=np.int64)
        local = np.empty(int(coff[-1]), dtype=np.int64)
        sizes = np.empty(int(foff[-1]), dtype=np.int64)
        for fk, G, _, n in self._parts:
            tf = _template_faces(n, r, quads)
            dest = (coff[fk][:, None] + np.arange(tf.size)).ravel()
            corners[dest] = G[:, tf.ravel()].ravel()
            local[dest] = (self.local_offsets[fk][:, None] + tf.ravel()).ravel()
            sizes[(foff[fk][:, None] + np.arange(len(tf))).ravel()] = tf.shape[1]
        offsets = np.zeros(len(sizes) + 1, dtype=np.int64)
        np.cumsum(sizes, out=offsets[1:])
        face = np.repeat(np.arange(tp.n_faces, dtype=np.int64), fcount)
        return _ro(offsets), _ro(corners), _ro(face), _ro(local)

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
        tp, r = self.topology, self.resolution
        V, E = tp.n_vertices, tp.n_edges
        sizes, fo, fv = tp.face_sizes, tp.face_offsets, tp.face_vertices
        if (r == 1 and np.any(sizes == 4) and not quads) or self.n_points >= 2 ** 31 - 1:
            return None
        i32 = np.int32
        S = np.empty((E, r + 1), dtype=i32)  # samples along each mesh edge
        S[:, 0], S[:, r] = tp.edges[:, 0], tp.edges[:, 1]
        S[:, 1:r] = V + np.arange(E * (r - 1), dtype=i32).reshape(E, r - 1)
        n_in = [int((_template_edges(n, r, quads)[2] < 0).sum()) * len(fk)
                for fk, _, _, n in self._parts]
        ev = np.empty((E * r + sum(n_in), 2), dtype=i32)
        ev[:E * r, 0] = S[:, :-1].ravel()
        ev[:E * r, 1] = S[:, 1:].ravel()
        coff = np.zeros(tp.n_faces + 1, dtype=np.int64)
        np.cumsum(self._corner_counts(quads), out=coff[1:])
        ce = np.empty(int(coff[-1]), dtype=i32)
        inner_of = np.empty(tp.n_faces + 1, dtype=np.int64)  # first inner edge id per face
        inner_of[-1] = len(ev)
        base = E * r
        for (fk, G, _, n), cnt in zip(self._parts, n_in):
            tedge, face_edge, side, seg = _template_edges(n, r, quads)
            ni = cnt // max(len(fk), 1)
            ids = np.empty((len(fk), len(tedge)), dtype=i32)
            ids[:, :ni] = base + np.arange(cnt, dtype=i32).reshape(len(fk), ni)
            inner_of[fk] = base + ni * np.arange(len(fk))
            h = fo[fk][:, None] + side[ni:][None, :]  # half-edge of the side
            e = tp.halfedge_edge[h]
            m = seg[ni:][None, :]
            ids[:, ni:] = e * r + np.where(fv[h] == tp.edges[e, 0], m, r - 1 - m)
            np.take(G.astype(i32), tedge[:ni].ravel(), axis=1, mode="clip",
                    out=ev[base:base + cnt].reshape(len(fk), 2 * ni))
            base += cnt
            got = np.take(ids, face_edge.ravel(), axis=1)  # (faces, corners of the template)
            if len(self._parts) == 1:
                ce[:] = got.ravel()
            else:
                ce[(coff[fk][:, None] + np.arange(face_edge.size)).ravel()] = got.ravel()
        weak = np.flatnonzero(~np.asarray(tp.vertex_is_boundary, dtype=bool)
                              & (np.diff(tp.star_offsets) <= 2))
        if len(weak):  # merge repeated inner edges of the faces around them
            so, sc = tp.star_offsets, tp.star_corners
            faces = np.unique(tp.corner_face[np.concatenate(
                [sc[so[w]:so[w + 1]] for w in weak.tolist()])])
            nin = {n: int((_template_edges(n, r, quads)[2] < 0).sum())
                   for _, _, _, n in self._parts}
            cand = np.concatenate([inner_of[f] + np.arange(nin[int(sizes[f])])
                                   for f in faces.tolist()])
            pair = np.sort(ev[cand], axis=1)
            _, first, inv = np.unique(pair, axis=0, return_index=True, return_inverse=True)
            if len(first) < len(cand):
                remap = np.arange(len(ev), dtype=i32)
                remap[cand] = cand[first[inv.ravel()]]
                keep = remap == np.arange(len(ev))
                remap = (np.cumsum(keep, dtype=i32) - 1)[remap]
                ev, ce = ev[keep], remap[ce]
        return ev, (ce if quads else ce.reshape(-1, 3))

    def template_params(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(uv (m, 2), fan (m,)) of every lattice point of an n-gon in template order: the
        local table of any face with n corners (``local_uv/local_fan[local_offsets[f]:
        local_offsets[f+1]]``), without building the whole table."""
        uv, fan = _template(int(n), self.resolution)[:2]
        return uv, fan

    def face_groups(self) -> tuple[np.ndarray, np.ndarray]:
        """(order (P,), offsets (F+1,)): ``order[offsets[f]:offsets[f+1]]`` are the samples
        evaluated in face f (``face[p] == f``), for per-face batched evaluation."""
        order = np.argsort(self.face, kind="stable")
        off = np.zeros(self.topology.n_faces + 1, dtype=np.int64)
        np.cumsum(np.bincount(self.face, minlength=self.topology.n_faces), out=off[1:])
        return order, off

    def corner_weights(self, local: bool = False) -> np.ndarray:
        """(P, n_max) weights of each sample's face corners (slot k = corner k of its face,
        0 beyond the face size): sum_k w_k X_k is :meth:`map_to_polygon` of per-corner
        values X (n-gon centres the corners' mean), as a linear map."""
        tp = self.topology
        face, fan, uv = ((self.local_face, self.local_fan, self.local_uv) if local
                         else (self.face, self.fan, self.uv))
        n = tp.face_sizes[face]
        a, b = uv[:, 0], uv[:, 1]
        w = np.zeros((len(face), int(tp.face_sizes.max())))
        s = n == 3
        if s.any():
            w[s, 0], w[s, 1], w[s, 2] = 1 - a[s] - b[s], a[s], b[s]
        s = n == 4
        if s.any():
            w[s, 0], w[s, 1] = (1 - a[s]) * (1 - b[s]), a[s] * (1 - b[s])
            w[s, 2], w[s, 3] = a[s] * b[s], (1 - a[s]) * b[s]
        s = np.flatnonzero(n >= 5)
        if len(s):
            w[s] = ((1 - a[s] - b[s]) / n[s])[:, None] * (np.arange(w.shape[1]) < n[s][:, None])
            w[s, fan[s]] += a[s]
            w[s, (fan[s] + 1) % n[s]] += b[s]
        return w

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
        tp = self.topology
        X = np.asarray(corners2d, dtype=np.float64)
        if X.ndim != 2 or X.shape[0] != tp.n_corners:
            raise InvalidParameterError("corners2d", f"must have shape ({tp.n_corners}, d), got "
                                        f"{X.shape}")
        face, fan, uv = ((self.local_face, self.local_fan, self.local_uv) if local
                         else (self.face, self.fan, self.uv))
        fo, n = tp.face_offsets[face], tp.face_sizes[face]
        a, b = uv[:, :1], uv[:, 1:]
        out = np.empty((len(face), X.shape[1]))
        s = n == 3
        c = fo[s]
        out[s] = (1 - a[s] - b[s]) * X[c] + a[s] * X[c + 1] + b[s] * X[c + 2]
        s = n == 4
        c = fo[s]
        out[s] = ((1 - a[s]) * (1 - b[s]) * X[c] + a[s] * (1 - b[s]) * X[c + 1]
                  + a[s] * b[s] * X[c + 2] + (1 - a[s]) * b[s] * X[c + 3])
        s = n >= 5
        if s.any():
            if centers is None:
                ctr = np.add.reduceat(X, tp.face_offsets[:-1], axis=0) / tp.face_sizes[:, None]
            else:
                ctr = np.asarray(centers, dtype=np.float64)
                if ctr.shape != (tp.n_faces, X.shape[1]):
                    raise InvalidParameterError("centers", f"must have shape ({tp.n_faces}, "
                                                f"{X.shape[1]}), got {ctr.shape}")
            k = fan[s]
            c0 = fo[s] + k
            c1 = fo[s] + (k + 1) % n[s]
            out[s] = (1 - a[s] - b[s]) * ctr[face[s]] + a[s] * X[c0] + b[s] * X[c1]
        return out
