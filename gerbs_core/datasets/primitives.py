"""Test and benchmark meshes.

Every function returns ``(vertices, faces)``: ``vertices`` is a (V,3) float64
array; ``faces`` is an (F,k) int64 array when all faces have k corners
(:func:`icosphere`, :func:`grid`, :func:`delaunay_patch`) and a list of int
tuples otherwise (:func:`uv_sphere`, :func:`mixed_mesh`, :func:`suzanne`).
Faces are oriented consistently and counter-clockwise seen from outside
(closed meshes: outward normals; flat meshes in z=0: normal +z).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError
from .obj import read_obj

__all__ = ["icosphere", "uv_sphere", "grid", "mixed_mesh", "delaunay_patch", "jittered_patch", "suzanne",
           "quad_patch", "ngon_ring", "fan", "cube", "cylinder", "cone", "torus", "SUZANNE_PATH"]

SUZANNE_PATH = Path(__file__).resolve().parents[2] / "examples" / "suzanne.obj"


def _check_int(name: str, value, lo: int) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InvalidParameterError(name, f"must be an integer, got {value!r}")
    if value < lo:
        raise InvalidParameterError(name, f"must be >= {lo}, got {value}")
    return int(value)


def icosphere(subdivisions: int = 2, radius: float = 1.0):
    """Unit icosphere: the icosahedron, each triangle split in 4 per level, projected to the sphere.

    V = 10*4**s + 2, F = 20*4**s triangles (s = subdivisions), closed, outward.
    """
    s = _check_int("subdivisions", subdivisions, 0)
    p = (1.0 + 5.0 ** 0.5) / 2.0
    v = np.array([[-1, p, 0], [1, p, 0], [-1, -p, 0], [1, -p, 0],
                  [0, -1, p], [0, 1, p], [0, -1, -p], [0, 1, -p],
                  [p, 0, -1], [p, 0, 1], [-p, 0, -1], [-p, 0, 1]], dtype=np.float64)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
                  [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
                  [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
                  [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int64)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(s):
        nv = len(v)
        e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])  # (3F,2)
        es = np.sort(e, axis=1)
        uniq, inv = np.unique(es, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        mid = v[uniq[:, 0]] + v[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        v = np.concatenate([v, mid])
        nf = len(f)
        ab, bc, ca = (nv + inv[:nf], nv + inv[nf:2 * nf], nv + inv[2 * nf:])
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        f = np.concatenate([np.stack([a, ab, ca], 1), np.stack([b, bc, ab], 1),
                            np.stack([c, ca, bc], 1), np.stack([ab, bc, ca], 1)])
    return v * float(radius), f


def uv_sphere(segments: int = 16, rings: int = 8, radius: float = 1.0):
    """UV sphere with `segments` meridians and `rings` latitude bands (Blender's convention).

    Vertex 0 is the north pole, the last vertex the south pole; both are single
    vertices with triangle fans of `segments` triangles; the other bands are
    quads. V = segments*(rings-1) + 2, F = segments*rings. Closed, outward.
    """
    n = _check_int("segments", segments, 3)
    m = _check_int("rings", rings, 2)
    theta = np.pi * np.arange(1, m) / m
    phi = 2.0 * np.pi * np.arange(n) / n
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    ring = np.stack([st * np.cos(phi), st * np.sin(phi), np.broadcast_to(ct, (m - 1, n))], -1)
    v = np.concatenate([[[0.0, 0.0, 1.0]], ring.reshape(-1, 3), [[0.0, 0.0, -1.0]]]) * float(radius)
    south = len(v) - 1
    idx = lambda i, j: 1 + i * n + (j % n)  # noqa: E731  (ring i, meridian j)
    faces = [(0, idx(0, j), idx(0, j + 1)) for j in range(n)]
    for i in range(m - 2):
        faces += [(idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)) for j in range(n)]
    faces += [(south, idx(m - 2, j + 1), idx(m - 2, j)) for j in range(n)]
    return v, faces


def grid(n: int = 4, m: int | None = None, kind: str = "quad", size: float = 1.0):
    """Flat grid of n x m square cells of side ``size / n`` in z=0: x in [0, size], y in [0, size*m/n].

    ``kind="quad"``: n*m quads; ``kind="tri"``: each cell split along the same
    diagonal (lower-left to upper-right), a regular triangle grid with interior
    valence 6. Vertex (i, j) has index ``j*(n+1) + i``. Boundary on all four sides.
    """
    n = _check_int("n", n, 1)
    m = n if m is None else _check_int("m", m, 1)
    if kind not in ("quad", "tri"):
        raise InvalidParameterError("kind", f"must be 'quad' or 'tri', got {kind!r}")
    h = float(size) / n
    jj, ii = np.meshgrid(np.arange(m + 1), np.arange(n + 1), indexing="ij")
    v = np.stack([ii.ravel() * h, jj.ravel() * h, np.zeros(ii.size)], 1)
    cj, ci = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")
    a = (cj * (n + 1) + ci).ravel()
    b, c, d = a + 1, a + n + 2, a + n + 1  # counter-clockwise seen from +z
    if kind == "quad":
        f = np.stack([a, b, c, d], 1)
    else:
        f = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return v, f.astype(np.int64)


def mixed_mesh(bend: float = 0.0):
    """A small mixed mesh: 17 triangles, 12 quads, a pentagon and a hexagon, with boundary.

    Built on a 6 x 4 square grid in the xy-plane (all faces strictly convex):
    the four cells around (1,1) are split into triangles (interior valence 8),
    a pentagon merges a cell with one of those triangles, a hexagon merges two
    cells (its two middle corners have valence 3), and further diagonals give
    interior valences 5, 6 and 7. Interior valences 3..8 all occur.
    ``bend`` lifts it to the gentle cylinder z = bend * ((x - 3) / 3)**2
    (non-planar pentagon and hexagon for bend != 0). V = 35, F = 31, E = 65.
    """
    gx, gy = np.meshgrid(np.arange(7.0), np.arange(5.0), indexing="xy")
    pts = np.stack([gx.ravel(), gy.ravel()], 1)  # g(i, j) -> index j*7 + i
    g = lambda i, j: j * 7 + i  # noqa: E731
    pts[g(4, 2)] = (4.0, 1.8)   # hexagon corners bulge out: strictly convex faces
    pts[g(4, 3)] = (4.0, 3.2)
    pts[g(2, 1)] = (2.0, 0.85)  # pentagon corner
    cells = {(i, j): (g(i, j), g(i + 1, j), g(i + 1, j + 1), g(i, j + 1))
             for i in range(6) for j in range(4)}
    faces = []
    used = set()

    def split(cell, through):
        """Split a cell into 2 triangles along the diagonal through corner `through`."""
        q = cells[cell]
        k = q.index(through)
        a, b, c, d = q[k:] + q[:k]
        used.add(cell)
        return [(a, b, c), (a, c, d)]

    tri_11 = []
    for cell in [(0, 0), (1, 0), (0, 1), (1, 1)]:  # valence 8 at g(1,1)
        tri_11 += split(cell, g(1, 1))
    # pentagon: cell (2,1) + triangle (g11, g21, g22) of cell (1,1)
    tri_11.remove((g(1, 1), g(2, 1), g(2, 2)))
    faces += tri_11
    faces.append((g(1, 1), g(2, 1), g(3, 1), g(3, 2), g(2, 2)))
    used.add((2, 1))
    # hexagon: cells (3,2) + (4,2); g(4,2), g(4,3) get valence 3
    faces.append((g(3, 2), g(4, 2), g(5, 2), g(5, 3), g(4, 3), g(3, 3)))
    used.update({(3, 2), (4, 2)})
    for cell in [(5, 1), (5, 2), (4, 1)]:  # valence 7 at g(5,2)
        faces += split(cell, g(5, 2))
    for cell in [(1, 3), (2, 3)]:  # valence 6 at g(2,3)
        faces += split(cell, g(2, 3))
    faces += [cells[c] for c in sorted(cells) if c not in used]
    v = np.concatenate([pts, np.zeros((len(pts), 1))], 1)
    v[:, 2] = float(bend) * ((v[:, 0] - 3.0) / 3.0) ** 2
    return v, faces


def delaunay_patch(n_points: int = 100, seed: int = 0, points=None):
    """Flat Delaunay triangulation of random points in the unit square (z = 0).

    The 4 corners of the square are always included, so the boundary is the
    square; the other ``n_points - 4`` points are uniform in the open square
    (``numpy.random.default_rng(seed)``). Alternatively pass ``points`` (N,2)
    to triangulate given points (the corners are then not added). Triangles
    are counter-clockwise seen from +z.
    """
    from scipy.spatial import Delaunay

    if points is None:
        n = _check_int("n_points", n_points, 4)
        rng = np.random.default_rng(seed)
        corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        xy = np.concatenate([corners, rng.uniform(0.0, 1.0, size=(n - 4, 2))])
    else:
        xy = np.array(points, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2 or len(xy) < 3:
            raise InvalidParameterError("points", f"must have shape (N>=3, 2), got {xy.shape}")
    tri = Delaunay(xy).simplices.astype(np.int64)
    p = xy[tri]
    area2 = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
             - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))
    tri[area2 < 0] = tri[area2 < 0][:, [0, 2, 1]]
    v = np.concatenate([xy, np.zeros((len(xy), 1))], 1)
    return v, tri


def jittered_patch(n_side: int, seed: int = 0, jitter: float = 0.35):
    """Flat Delaunay mesh of a jittered ``n_side x n_side`` grid on the unit square.

    Boundary points stay evenly spaced and interior points move by at most
    ``jitter * h`` (h = 1/(n_side-1)) in each coordinate, so the mesh size is
    uniform (h) everywhere, unlike :func:`delaunay_patch`, whose boundary
    triangles never refine. Used for convergence studies.
    """
    n = _check_int("n_side", n_side, 2)
    g = np.linspace(0.0, 1.0, n)
    X, Y = np.meshgrid(g, g)
    xy = np.stack([X.ravel(), Y.ravel()], 1)
    inner = (xy > 1e-12).all(1) & (xy < 1 - 1e-12).all(1)
    h = 1.0 / (n - 1)
    xy[inner] += np.random.default_rng(seed).uniform(-jitter * h, jitter * h, (int(inner.sum()), 2))
    return delaunay_patch(points=xy)


def quad_patch(n: int = 4, m: int | None = None, seed: int = 0, split: float = 0.3,
               jitter: float = 0.2, holes: float = 0.0):
    """Quad-dominant flat patch: an n x m grid of the unit square's width, jittered.

    Interior vertices move by at most ``jitter * h`` per coordinate (h = 1/n; jitter
    < 0.5 keeps every quad strictly convex); each cell is a quad or, with
    probability ``split``, two triangles along a random diagonal; with probability
    ``holes`` a cell at odd (i, j), 0 < i < n-1, 0 < j < m-1 is left out (such holes
    never touch each other or the outer boundary, so the mesh stays manifold).
    Faces are a list of tuples, counter-clockwise seen from +z.
    """
    n = _check_int("n", n, 1)
    m = n if m is None else _check_int("m", m, 1)
    if not 0.0 <= jitter < 0.5:
        raise InvalidParameterError("jitter", f"must be in [0, 0.5), got {jitter}")
    rng = np.random.default_rng(seed)
    v, _ = grid(n, m)
    h = 1.0 / n
    i, j = np.arange(len(v)) % (n + 1), np.arange(len(v)) // (n + 1)
    inner = (i > 0) & (i < n) & (j > 0) & (j < m)
    v[inner, :2] += rng.uniform(-jitter * h, jitter * h, (int(inner.sum()), 2))
    faces = []
    for cj in range(m):
        for ci in range(n):
            if (ci % 2 and cj % 2 and 0 < ci < n - 1 and 0 < cj < m - 1
                    and rng.random() < holes):
                continue
            a = cj * (n + 1) + ci
            q = (a, a + 1, a + n + 2, a + n + 1)
            if rng.random() < split:
                faces += ([(q[0], q[1], q[2]), (q[0], q[2], q[3])] if rng.random() < 0.5
                          else [(q[0], q[1], q[3]), (q[1], q[2], q[3])])
            else:
                faces.append(q)
    used = np.unique(np.concatenate([np.asarray(f) for f in faces]))
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))  # holes never orphan a vertex; kept for safety
    return v[used], [tuple(int(remap[k]) for k in f) for f in faces]


def ngon_ring(n: int = 6, seed: int = 0, split: float = 0.5, twist: float = 0.2):
    """A regular n-gon (n >= 3) surrounded by a ring of n quads, each split into two
    triangles with probability ``split``; outer ring radius 2.5, rotated by ``twist``.

    The n-gon's corners have valence 3 or 4; flat (z = 0), boundary = the outer ring.
    """
    n = _check_int("n", n, 3)
    rng = np.random.default_rng(seed)
    t = 2 * np.pi * np.arange(n) / n
    inner = np.stack([np.cos(t), np.sin(t)], 1)
    outer = 2.5 * np.stack([np.cos(t + twist), np.sin(t + twist)], 1)
    v = np.concatenate([np.concatenate([inner, outer]), np.zeros((2 * n, 1))], 1)
    faces = [tuple(range(n))]
    for k in range(n):
        q = ((k + 1) % n, k, n + k, n + (k + 1) % n)  # counter-clockwise from +z
        if rng.random() < split:
            faces += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
        else:
            faces.append(q)
    return v, faces


def fan(k: int = 6, height: float = 0.0, closed: bool = False):
    """k triangles around a centre vertex 0 at (0, 0, height) (a cone; valence k).

    Rim vertices 1..k on the unit circle in z = 0. ``closed``: add a second apex
    (vertex k+1 at (0, 0, -height), or -1 if height = 0) with its own fan, a closed
    bipyramid with two valence-k apices and valence-4 rim vertices (outward normals).
    """
    k = _check_int("k", k, 3)
    t = 2 * np.pi * np.arange(k) / k
    rim = np.stack([np.cos(t), np.sin(t), np.zeros(k)], 1)
    top = [(0, 1 + i, 1 + (i + 1) % k) for i in range(k)]
    if not closed:
        return np.concatenate([[[0.0, 0.0, float(height)]], rim]), top
    h = float(height) if height != 0.0 else 1.0
    v = np.concatenate([[[0.0, 0.0, h]], rim, [[0.0, 0.0, -h]]])
    bottom = [(k + 1, 1 + (i + 1) % k, 1 + i) for i in range(k)]
    return v, top + bottom


def cube(size: float = 2.0):
    """Blender's default Cube: 8 vertices at +-size/2, 6 quads."""
    h = 0.5 * float(size)
    V = np.array([(x, y, z) for x in (-h, h) for y in (-h, h) for z in (-h, h)])
    F = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4],
                  [1, 5, 7, 3]], dtype=np.int64)
    return V, F


def _ring(n: int, radius: float, z: float):
    t = 2 * np.pi * np.arange(n) / n
    return np.stack([radius * np.cos(t), radius * np.sin(t), np.full(n, float(z))], 1)


def cylinder(n: int = 32, radius: float = 1.0, depth: float = 2.0):
    """Blender's default Cylinder: n side quads and two n-gon caps (no cap centres)."""
    n = _check_int("n", n, 3)
    V = np.concatenate([_ring(n, radius, -0.5 * depth), _ring(n, radius, 0.5 * depth)])
    F = [(i, (i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)]
    F += [tuple(range(n - 1, -1, -1)), tuple(range(n, 2 * n))]
    return V, F


def cone(n: int = 32, radius: float = 1.0, depth: float = 2.0):
    """Blender's default Cone: n side triangles to the apex and an n-gon base."""
    n = _check_int("n", n, 3)
    V = np.concatenate([_ring(n, radius, -0.5 * depth), [[0.0, 0.0, 0.5 * depth]]])
    F = [(i, (i + 1) % n, n) for i in range(n)] + [tuple(range(n - 1, -1, -1))]
    return V, F


def torus(n_major: int = 24, n_minor: int = 16, major: float = 1.0, minor: float = 0.4):
    """A quad torus with its vertices exactly on the torus (major radius R, minor r)."""
    n_major, n_minor = _check_int("n_major", n_major, 3), _check_int("n_minor", n_minor, 3)
    u = 2 * np.pi * np.arange(n_major) / n_major
    v = 2 * np.pi * np.arange(n_minor) / n_minor
    U, W = np.meshgrid(u, v, indexing="ij")
    rho = major + minor * np.cos(W)
    V = np.stack([rho * np.cos(U), rho * np.sin(U), minor * np.sin(W)], -1).reshape(-1, 3)
    idx = lambda i, j: (i % n_major) * n_minor + (j % n_minor)  # noqa: E731
    F = np.array([[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]
                  for i in range(n_major) for j in range(n_minor)], dtype=np.int64)
    return V, F


def suzanne():
    """Blender's Suzanne (examples/suzanne.obj): 507 vertices, 500 faces (468 quads, 32 triangles)."""
    return read_obj(SUZANNE_PATH)
