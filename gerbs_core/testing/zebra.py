"""Zebra stripes as a number: how many pieces the reflection-line bands of a triangle
mesh break into (the common yardstick of bench_shape's "zebra" column).

A modeller reads a zebra rendering by its stripes: on a fair surface each band runs on
in long loops, on a bumpy one it breaks into islands (every bump and dimple is a local
extremum of n . a, ringed by its own closed stripe). :func:`stripe_components` counts
those pieces. For a unit direction a (the environment's axis) a point with unit normal n
lies in the band

    b = floor(stripes * asin(n . a) / pi)        (b in -ceil(stripes/2) .. stripes/2)

(the bands of the figures' zebra shader, scripts/figures/materials.zebra, with the normal
standing in for the view-dependent reflected ray, so the count needs no camera). Two
mesh vertices joined by a triangle edge and lying in the same band are in the same
piece; the figure is the number of connected pieces, averaged over ``directions`` axes
spread evenly over the sphere (a Fibonacci lattice: no axis is favoured).

Known answers: a finely sampled sphere has one piece per band for every axis (9 stripes:
10 pieces, the two polar caps and eight rings); every bump adds at least one. Exact
counting on the given mesh; the figure depends on the sampling density (compare meshes
of matched density, as bench_shape does) and on the normals (default: angle-weighted
vertex normals, :func:`~gerbs_core.testing.fairness.vertex_normals`, what a smooth-shaded
mesh shows).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import InvalidParameterError
from .fairness import _mesh, vertex_normals

__all__ = ["sphere_directions", "stripe_components"]


def sphere_directions(n: int) -> np.ndarray:
    """(n, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice:
    equal-area latitude steps, golden-angle longitudes); deterministic."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    t = np.pi * (1.0 + np.sqrt(5.0)) * i
    return np.stack([r * np.cos(t), r * np.sin(t), z], axis=1)


def stripe_components(points, triangles, normals=None, *, stripes: float = 9.0,
                      directions: int = 24) -> float:
    """Mean number of connected zebra stripes (module docstring) of the mesh.

    points (P, 3), triangles (T, 3) int; normals (P, 3) unit vectors or None (the
    angle-weighted vertex normals). Only points of some triangle with a finite normal
    are counted. stripes > 0: black and white bands per half turn; directions >= 1 axes.
    Returns the mean over the axes of the number of pieces (a float >= 1 on a non-empty
    mesh; fewer is fairer at the same sampling density).
    """
    P, T = _mesh(points, triangles)
    if not (np.isfinite(stripes) and stripes > 0):
        raise InvalidParameterError("stripes", f"must be finite and > 0, got {stripes!r}")
    if int(directions) != directions or directions < 1:
        raise InvalidParameterError("directions", f"must be an integer >= 1, got {directions!r}")
    N = vertex_normals(P, T) if normals is None else np.asarray(normals, dtype=np.float64)
    if N.shape != P.shape:
        raise InvalidParameterError("normals", f"must have the points' shape {P.shape}, got {N.shape}")
    live = np.zeros(len(P), dtype=bool)
    live[T.reshape(-1)] = True
    live &= np.isfinite(N).all(axis=1)
    ids = np.cumsum(live) - 1                      # the counted points, renumbered
    e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    e = ids[e[live[e].all(axis=1)]]
    Nl, n = N[live], int(live.sum())
    if n == 0:
        return 0.0
    counts = []
    for a in sphere_directions(int(directions)):
        band = np.floor(stripes * np.arcsin(np.clip(Nl @ a, -1.0, 1.0)) / np.pi)
        same = e[band[e[:, 0]] == band[e[:, 1]]]
        graph = sp.coo_matrix((np.ones(len(same)), (same[:, 0], same[:, 1])), shape=(n, n))
        counts.append(connected_components(graph, directed=False)[0])
    return float(np.mean(counts))
