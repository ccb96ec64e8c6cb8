"""Shape metrics of triangle meshes: the common yardstick of every surface method.

Inputs are an output mesh ``points`` (P, 3) float64 and ``triangles`` (T, 3) int
(0-based, counter-clockwise seen from the side the normals point to). Nothing
here knows how the mesh was made, so GERBS, subdivision and exact samplings are
measured by the same rules. Everything is exact arithmetic on the given mesh
except where a docstring says "estimate" (the cotangent mean curvature is a
consistent estimate of the smooth surface's on well-shaped meshes, Meyer et al.
2003; it is not convergent on arbitrary irregular meshes).

Sign convention (see :mod:`gerbs_core.testing`): H > 0 where the surface bends
away from its normal; the unit sphere with outward normals has H = +1.
"""
from __future__ import annotations

import numpy as np

from ..mesh.triangle_edges import edge_runs

__all__ = ["triangle_normals", "edge_adjacency", "orientation_defects", "dihedral_angles",
           "fold_counts", "vertex_normals", "mixed_areas", "cotangent_mean_curvature",
           "mean_curvature_from_derivatives", "box_ratio", "observed_order"]


def _mesh(points, triangles):
    P = np.asarray(points, dtype=np.float64)
    T = np.asarray(triangles, dtype=np.int64)
    if P.ndim != 2 or P.shape[1] != 3:
        raise ValueError(f"points must have shape (P, 3), got {P.shape}")
    if T.ndim != 2 or T.shape[1] != 3:
        raise ValueError(f"triangles must have shape (T, 3), got {T.shape}")
    if len(T) and (T.min() < 0 or T.max() >= len(P)):
        raise ValueError("triangles index points out of range")
    return P, T


def _unit(v):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)


def _scatter(index, values, n):
    """sum of values (N,) or (N, k) per index (N,) into n slots (np.add.at, faster)."""
    if values.ndim == 1:
        return np.bincount(index, weights=values, minlength=n)
    return np.stack([np.bincount(index, weights=values[:, k], minlength=n)
                     for k in range(values.shape[1])], axis=1)


def triangle_normals(points, triangles):
    """(unit normals (T, 3), areas (T,)) of the triangles; a zero-area triangle
    gets the normal 0 (it is left out of every angle below)."""
    P, T = _mesh(points, triangles)
    c = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    a = 0.5 * np.linalg.norm(c, axis=1)
    return _unit(c), a


def edge_adjacency(triangles):
    """Edges of a triangle mesh and the triangles on each side.

    Returns dict with
      ``pairs`` (E2, 2): the two triangles of every edge with exactly two;
      ``pair_edges`` (E2, 2): its vertices (as first met, in the first triangle's
      direction); ``same_direction`` (E2,) bool: both triangles traverse the edge
      the same way (orientation defect);
      ``boundary_edges`` (Eb, 2): edges of one triangle;
      ``n_nonmanifold``: number of edges with three or more triangles.
    """
    T = np.asarray(triangles, dtype=np.int64)
    m = len(T)
    order, start, count = edge_runs(T)
    tri = order % m
    corner = order // m
    d = np.stack([T[tri, corner], T[tri, (corner + 1) % 3]], axis=1)  # half-edges, sorted
    two = start[count == 2]
    return {
        "pairs": np.stack([tri[two], tri[two + 1]], axis=1),
        "pair_edges": d[two],
        "same_direction": np.all(d[two] == d[two + 1], axis=1),
        "boundary_edges": d[start[count == 1]],
        "n_nonmanifold": int(np.sum(count > 2)),
    }


def orientation_defects(triangles) -> int:
    """Number of two-triangle edges traversed in the same direction by both
    triangles: 0 for a consistently oriented mesh (then the normals of
    :func:`triangle_normals` / :func:`vertex_normals` are orientation-consistent
    and signed curvatures are meaningful)."""
    return int(np.sum(edge_adjacency(triangles)["same_direction"]))


def dihedral_angles(points, triangles, adjacency=None):
    """Angle in degrees (E2,) between the unit normals of the two triangles at
    every two-triangle edge: 0 where they are coplanar, 180 where one folds back
    onto the other (orientation-consistent meshes). Edges next to a zero-area
    triangle are left out (the result is shorter then; ``adjacency`` from
    :func:`edge_adjacency` may be passed to save its work)."""
    n, a = triangle_normals(points, triangles)
    adj = edge_adjacency(triangles) if adjacency is None else adjacency
    i, j = adj["pairs"].T
    ok = (a[i] > 0) & (a[j] > 0)
    c = np.clip(np.einsum("ij,ij->i", n[i[ok]], n[j[ok]]), -1.0, 1.0)
    # arctan2 of |cross| and dot is accurate near 0 and 180 degrees, unlike arccos
    s = np.linalg.norm(np.cross(n[i[ok]], n[j[ok]]), axis=1)
    return np.degrees(np.arctan2(s, c))


def fold_counts(points, triangles, thresholds=(60.0, 90.0)):
    """Folds: dict with ``above_<t>`` (number of adjacent triangle pairs whose
    normals differ by more than t degrees, for each threshold), ``max`` (the
    largest dihedral angle, degrees; 0 without interior edges) and ``pairs``
    (the number of pairs measured)."""
    ang = dihedral_angles(points, triangles)
    out = {f"above_{t:g}": int(np.sum(ang > t)) for t in thresholds}
    out["max"] = float(ang.max()) if len(ang) else 0.0
    out["pairs"] = int(len(ang))
    return out


def _corner_geometry(P, T):
    """Per triangle and corner k (opposite the edge k+1 -> k+2): cot (T, 3) of the
    corner's angle, double area (T,), squared length (T, 3) of the opposite edge."""
    e = [P[T[:, (k + 2) % 3]] - P[T[:, (k + 1) % 3]] for k in range(3)]  # edge opposite k
    dbl = np.linalg.norm(np.cross(e[0], e[1]), axis=1)
    cot = np.empty((len(T), 3))
    for k in range(3):
        u, v = -e[(k + 2) % 3], e[(k + 1) % 3]  # from corner k to k+1 and to k+2
        cot[:, k] = np.einsum("ij,ij->i", u, v)
    with np.errstate(divide="ignore", invalid="ignore"):
        cot = np.where(dbl[:, None] > 0, cot / dbl[:, None], 0.0)
    sq = np.stack([np.einsum("ij,ij->i", x, x) for x in e], axis=1)
    return cot, dbl, sq


def vertex_normals(points, triangles):
    """Unit vertex normals (P, 3), each the sum of its triangles' unit normals
    weighted by the corner angles (Thuermer and Wuethrich 1998); an
    unreferenced point gets 0. Orientation-consistent when the triangles are
    (check with :func:`orientation_defects`)."""
    P, T = _mesh(points, triangles)
    n, _ = triangle_normals(P, T)
    cot, _, _ = _corner_geometry(P, T)
    ang = np.arctan2(1.0, cot)  # angle in (0, pi) from its cotangent
    acc = sum(_scatter(T[:, k], ang[:, k, None] * n, len(P)) for k in range(3))
    return _unit(acc)


def boundary_points(triangles, n_points: int, adjacency=None):
    """(n_points,) bool: points on an edge that has one triangle."""
    adj = edge_adjacency(triangles) if adjacency is None else adjacency
    mask = np.zeros(n_points, dtype=bool)
    mask[adj["boundary_edges"].ravel()] = True
    return mask


def _mixed_areas(P, T, cot, dbl, sq):
    area = 0.5 * dbl
    obtuse = cot < 0
    any_obt = obtuse.any(axis=1)
    A = np.zeros(len(P))
    for k in range(3):
        k1, k2 = (k + 1) % 3, (k + 2) % 3
        vor = (sq[:, k2] * cot[:, k2] + sq[:, k1] * cot[:, k1]) / 8.0  # edges at corner k
        part = np.where(any_obt, np.where(obtuse[:, k], area / 2.0, area / 4.0), vor)
        A += _scatter(T[:, k], part, len(P))
    return A


def mixed_areas(points, triangles):
    """Mixed area (P,) of every point (Meyer et al. 2003, Fig. 4): the Voronoi
    region's share of each non-obtuse triangle at the point, and of an obtuse
    triangle half its area at the obtuse corner, a quarter at the other two.
    Positive, and summing to the mesh's area."""
    P, T = _mesh(points, triangles)
    return _mixed_areas(P, T, *_corner_geometry(P, T))


def cotangent_mean_curvature(points, triangles, normals=None, adjacency=None):
    """Estimate of the signed mean curvature at the interior points (Meyer, Desbrun,
    Schroeder and Barr 2003, "Discrete differential-geometry operators").

    K_i = 1/(2 A_i) sum_j (cot a_ij + cot b_ij)(x_i - x_j), the mean-curvature
    normal 2 H n, with the mixed (Voronoi / obtuse-safe) area A_i; returns
    ``(H (P,), interior (P,) bool)`` with H_i = |K_i| / 2 signed by K_i . n_i,
    n_i the angle-weighted vertex normal (or the given ``normals`` (P, 3)). NaN
    where it is undefined: boundary points, unreferenced points, zero area.
    Zero-area triangles contribute nothing. ``adjacency``: :func:`edge_adjacency`
    of the triangles, if at hand.
    """
    P, T = _mesh(points, triangles)
    cot, dbl, sq = _corner_geometry(P, T)
    K = np.zeros_like(P)
    for k in range(3):
        a, b = T[:, (k + 1) % 3], T[:, (k + 2) % 3]  # the edge opposite corner k
        w = cot[:, k, None] * (P[a] - P[b])
        K += _scatter(np.concatenate([a, b]), np.concatenate([w, -w]), len(P))
    A = _mixed_areas(P, T, cot, dbl, sq)
    interior = np.zeros(len(P), dtype=bool)
    interior[np.unique(T)] = True
    interior &= ~boundary_points(T, len(P), adjacency)
    n = vertex_normals(P, T) if normals is None else np.asarray(normals, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        K = K / (2.0 * A[:, None])
        H = 0.5 * np.linalg.norm(K, axis=1) * np.sign(np.einsum("ij,ij->i", K, n))
    H[~interior | ~(A > 0)] = np.nan
    return H, interior


def mean_curvature_from_derivatives(dS, d2S):
    """Exact mean curvature (N,) of a parametrization S(u) from its derivatives.

    dS (N, 3, 2): dS_i/du_j; d2S (N, 3, 2, 2): d2S_i/du_j du_k. With the unit
    normal n = S_1 x S_2 / |S_1 x S_2| (the orientation of the parametrization),
    the fundamental forms I = [[E, F], [F, G]], II = [[L, M], [M, N]] (L = S_11 . n),
    H = -(E N - 2 F M + G L) / (2 (E G - F^2)), positive where the surface bends
    away from n (unit sphere, outward n: +1). NaN where S is singular.
    """
    dS = np.asarray(dS, dtype=np.float64)
    d2S = np.asarray(d2S, dtype=np.float64)
    s1, s2 = dS[..., 0], dS[..., 1]
    n = _unit(np.cross(s1, s2))
    E, F, G = (np.einsum("...i,...i->...", a, b) for a, b in ((s1, s1), (s1, s2), (s2, s2)))
    L, M, N = (np.einsum("...i,...i->...", d2S[..., j, k], n) for j, k in ((0, 0), (0, 1), (1, 1)))
    det = E * G - F * F
    with np.errstate(divide="ignore", invalid="ignore"):
        H = -(E * N - 2.0 * F * M + G * L) / (2.0 * det)
    return np.where(det > 0, H, np.nan)


def box_ratio(points, cage):
    """Extent of the output's axis-aligned bounding box over the cage's, per axis
    (3,): 1 means the same size; NaN on an axis where the cage is flat."""
    P, C = np.asarray(points, dtype=np.float64), np.asarray(cage, dtype=np.float64)
    out, cg = np.ptp(P, axis=0), np.ptp(C, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cg > 0, out / cg, np.nan)


def observed_order(h, err) -> float:
    """Observed order p of err ~ C h^p: the least-squares slope of log err against
    log h (h, err (n,) positive, n >= 2). NaN if an error is not positive."""
    h, e = np.asarray(h, dtype=np.float64), np.asarray(err, dtype=np.float64)
    if len(h) != len(e) or len(h) < 2:
        raise ValueError("need at least two (h, err) pairs of equal length")
    if not (np.all(h > 0) and np.all(e > 0) and np.all(np.isfinite(e))):
        return float("nan")
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])
