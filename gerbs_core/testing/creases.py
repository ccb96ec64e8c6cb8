"""Measuring creases of a tessellated surface: normal jumps across output edges and the
crease curves along creased mesh edges (tests, figures, benchmarks).

A tessellation's triangles meet at an output edge with a dihedral angle of O(h) where the
surface is smooth (h the sample spacing) and O(1) where it has a crease. So
:func:`normal_jumps` splits the dihedral angles of all output edges into those lying on
given mesh edges (the samples of :class:`gerbs_core.mesh.lattice.Lattice` along them)
and the rest: a creased edge shows a jump that does not shrink with the resolution,
everything else angles that do.
"""
from __future__ import annotations

import numpy as np

from .fairness import edge_adjacency, triangle_normals

__all__ = ["normal_jumps", "on_mesh_edges", "chain_polyline", "turning_angles"]


def on_mesh_edges(lattice, topology, edge_mask, pairs) -> np.ndarray:
    """(K,) bool: output edges ``pairs`` (K, 2) of sample indices that lie on a mesh edge
    with ``edge_mask`` (E,) True (both ends among its samples: its interior samples and
    its end vertices)."""
    V, E = topology.n_vertices, topology.edges
    es = lattice.edge_samples
    owner = np.full(lattice.n_points, -1)
    owner[es.ravel()] = np.repeat(np.arange(topology.n_edges), es.shape[1])
    mask = np.asarray(edge_mask, dtype=bool)

    def one(a, b):
        e = owner[a]
        ok = (e >= 0) & mask[np.maximum(e, 0)]
        ends = E[np.maximum(e, 0)]
        return ok & ((owner[b] == e) | ((b < V) & ((ends[:, 0] == b) | (ends[:, 1] == b))))

    p, q = np.asarray(pairs).T
    return one(p, q) | one(q, p)


def normal_jumps(points, triangles, lattice, topology, edge_mask):
    """(on (K1,), off (K2,)): dihedral angles in degrees of the output edges lying on the
    masked mesh edges and of all other two-triangle output edges (edges next to a zero-area
    triangle left out)."""
    adj = edge_adjacency(triangles)
    n, a = triangle_normals(points, triangles)
    i, j = adj["pairs"].T
    ok = (a[i] > 0) & (a[j] > 0)
    c = np.clip(np.einsum("ij,ij->i", n[i], n[j]), -1.0, 1.0)
    s = np.linalg.norm(np.cross(n[i], n[j]), axis=1)
    ang = np.degrees(np.arctan2(s, c))
    on = on_mesh_edges(lattice, topology, edge_mask, adj["pair_edges"])
    return ang[on & ok], ang[~on & ok]


def chain_polyline(lattice, topology, chain_vertices, closed) -> np.ndarray:
    """Sample indices along a chain of mesh edges through ``chain_vertices`` (n,) in order:
    each vertex sample, then the interior samples of the edge to the next vertex."""
    E = topology.edges
    V = topology.n_vertices
    code = E[:, 0] * V + E[:, 1]
    vs = list(np.asarray(chain_vertices, dtype=np.int64))
    stops = vs + ([vs[0]] if closed else [])
    out = []
    for a, b in zip(stops[:-1], stops[1:]):
        e = int(np.flatnonzero(code == min(a, b) * V + max(a, b))[0])
        inner = lattice.edge_samples[e]
        out.append(a)
        out.extend((inner if E[e, 0] == a else inner[::-1]).tolist())
    out.append(stops[-1])
    return np.array(out, dtype=np.int64)


def turning_angles(points) -> np.ndarray:
    """(n - 2,) angles in degrees between consecutive segments of a polyline (n, 3)."""
    d = np.diff(np.asarray(points, dtype=np.float64), axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    c = np.clip(np.einsum("ij,ij->i", d[:-1], d[1:]), -1.0, 1.0)
    s = np.linalg.norm(np.cross(d[:-1], d[1:]), axis=1)
    return np.degrees(np.arctan2(s, c))
