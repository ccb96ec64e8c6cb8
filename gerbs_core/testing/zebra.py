"""Zebra stripes as a number: how many visible pieces the reflection-line bands of a
triangle mesh break into (the common yardstick of bench_shape's "zebra" column).

A modeller reads a zebra rendering by its stripes: on a fair surface each band runs on
in long loops, on a bumpy one it breaks into islands (a bump or dimple steep enough to be
its own extremum of n . a is ringed by its own closed stripe). :func:`stripe_components`
counts those pieces. For a unit direction a (the environment's axis) a point with unit
normal n lies in the band

    b = floor(stripes * asin(n . a) / pi)

The figures' shader (scripts/figures/materials.zebra) bands the reflected view ray
instead, which turns twice as fast as the normal: ``stripes`` = 18 here has the density
of the shader's default 9 (the README figures use 10 to 22 there, i.e. 20 to 44 here; the
peer figures 10 and 12: 20 and 24 here). The normal makes the count
independent of a camera. Two mesh vertices joined by a triangle edge and lying in the
same band are in the same piece. A piece counts if it covers at least ``min_area`` of the
mesh's area (each vertex carrying a third of its triangles' areas): specks of a few
vertices, where a band's edge grazes the rounding of the normals, are not what a
rendering shows as islands (on Suzanne at r = 8 and 18 stripes there are 2,548 pieces
in all, 702 of at least 1e-4 of the area and 166 of at least 1e-3). The figure is the
number of pieces averaged over ``directions`` axes spread evenly over the sphere (a
Fibonacci lattice: no axis is favoured).

Known answers: a finely sampled sphere has one piece per band for every axis (18
stripes: 18 pieces, two polar caps and sixteen rings); a bump steep enough adds pieces, a
gentle one adds none, as in a rendering. Exact counting on the given mesh; the figure
depends on the sampling density (compare meshes of matched density, as bench_shape
does) and on the normals (default: angle-weighted vertex normals,
:func:`~gerbs_core.testing.fairness.vertex_normals`, what a smooth-shaded mesh shows).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import InvalidParameterError
from ..mesh.triangle_edges import edge_runs
from .fairness import _mesh, triangle_normals, vertex_normals

__all__ = ["sphere_directions", "stripe_components"]


def sphere_directions(n: int) -> np.ndarray:
    """(n, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice:
    equal-area latitude steps, golden-angle longitudes); deterministic."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    t = np.pi * (1.0 + np.sqrt(5.0)) * i
    return np.stack([r * np.cos(t), r * np.sin(t), z], axis=1)


def _check(stripes, directions, min_area) -> tuple[int, np.ndarray]:
    if not (np.isfinite(stripes) and stripes > 0):
        raise InvalidParameterError("stripes", f"must be finite and > 0, got {stripes!r}")
    if not (np.isfinite(directions) and int(directions) == directions and directions >= 1):
        raise InvalidParameterError("directions", f"must be an integer >= 1, got {directions!r}")
    m = np.asarray(min_area, dtype=np.float64)
    if m.ndim > 1 or not m.size or not (np.isfinite(m) & (m >= 0) & (m < 1)).all():
        raise InvalidParameterError("min_area", f"must be in [0, 1) (or a list of such), got {min_area!r}")
    return int(directions), m


def stripe_components(points, triangles, normals=None, *, stripes: float = 18.0,
                      directions: int = 24, min_area=1e-3):
    """Mean number of visible zebra pieces (module docstring) of the mesh.

    points (P, 3), triangles (T, 3) int; normals (P, 3) (made unit) or None (the
    angle-weighted vertex normals). Only points of some triangle with finite positions
    and a non-zero finite normal are counted (a degenerate point's zero normal is not). stripes > 0:
    bands per half turn of the normal (18: the figures' density); directions >= 1 axes;
    min_area in [0, 1): the fraction of the mesh's area a piece must cover to count
    (0: every piece), or a list of such fractions (one pass for all). Returns the mean
    over the axes, a float (an array (k,) for k fractions); fewer is fairer at the same
    sampling density; 0.0 for a mesh without triangles.
    """
    P, T = _mesh(points, triangles)
    nd, floors = _check(stripes, directions, min_area)
    zero = 0.0 if floors.ndim == 0 else np.zeros(floors.shape)
    if normals is not None:
        N = np.asarray(normals, dtype=np.float64)
        if N.shape != P.shape:
            raise InvalidParameterError("normals", f"must have the points' shape {P.shape}, got {N.shape}")
    if not len(T):
        return zero
    N = vertex_normals(P, T) if normals is None else N
    live = np.zeros(len(P), dtype=bool)
    live[T.reshape(-1)] = True
    with np.errstate(invalid="ignore", divide="ignore"):
        length = np.sqrt(np.einsum("ij,ij->i", N, N))
        # given normals of any length are made unit; a zero one (a degenerate point's
        # vertex normal) is not a direction and the point is not counted
        live &= np.isfinite(P).all(axis=1) & np.isfinite(length) & (length > 1e-12)
        N = N / length[:, None]
    n = int(live.sum())
    if n == 0:
        return zero
    ids = np.cumsum(live, dtype=np.int64) - 1      # the counted points, renumbered
    _, tri_area = triangle_normals(P, T)
    tri_area = np.where(np.isfinite(tri_area), tri_area, 0.0)
    area = np.bincount(T.reshape(-1), np.repeat(tri_area / 3.0, 3), minlength=len(P))[live]
    need = np.atleast_1d(floors) * area.sum()
    # each edge once (its first half-edge in the sorted runs): half the work below
    order, start, _ = edge_runs(T)
    h = order[start]
    tri, corner = h % len(T), h // len(T)
    e = np.stack([T[tri, corner], T[tri, (corner + 1) % 3]], axis=1)
    e = ids[e[live[e].all(axis=1)]]
    Nl = N[live]
    counts = np.zeros((nd, len(need)))
    for i, a in enumerate(sphere_directions(nd)):
        band = np.floor(stripes * np.arcsin(np.clip(Nl @ a, -1.0, 1.0)) / np.pi)
        same = e[band[e[:, 0]] == band[e[:, 1]]]
        graph = sp.coo_matrix((np.ones(len(same)), (same[:, 0], same[:, 1])), shape=(n, n))
        k, label = connected_components(graph, directed=False)
        pieces = np.bincount(label, area, minlength=k)
        counts[i] = (pieces[:, None] >= need).sum(axis=0)
    mean = counts.mean(axis=0)
    return float(mean[0]) if floors.ndim == 0 else mean
