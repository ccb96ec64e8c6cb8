"""Columns of the coupled-fits map computed on a neighbourhood of the moved vertices.

Column j of the coefficient operator (:class:`gerbs_core.mesh.coupling.CoupledFits`)
is the map applied to the unit vector e_j. Its nonzeros lie within a few rings of j
(the data rings plus one ring per coupling sweep), and every intermediate of the map
does too; so restricting every matrix of the map to a neighbourhood S of j that
contains that support with a margin gives the same column (exact: the rows and columns
left out hold zeros). The cost is then that of S, not of the mesh: what a drag in Edit
Mode needs. S is grown in the graph of the chosen data fits (vertex i ~ j when i's data
fit uses j), ``reach`` hops.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["vertex_graph", "neighbourhood", "local_parts"]


def vertex_graph(chosen, n_vertices: int) -> sp.csr_matrix:
    """(V, V) symmetric pattern: i ~ j when a coefficient row of i has a column j."""
    c = chosen.tocoo()
    mmax = c.shape[0] // n_vertices
    g = sp.csr_matrix((np.ones(c.nnz, dtype=np.int8), (c.row // mmax, c.col)),
                      shape=(n_vertices, n_vertices))
    g = (g + g.T).tocsr()
    g.sum_duplicates()
    return g


def neighbourhood(graph, seeds, hops: int) -> np.ndarray:
    """Sorted vertices within ``hops`` steps of ``seeds`` in ``graph`` (local: touches the
    rows it reaches only)."""
    seen = np.zeros(graph.shape[0], dtype=bool)
    front = np.unique(np.asarray(seeds, dtype=np.int64))
    seen[front] = True
    ptr, ind = graph.indptr, graph.indices
    for _ in range(hops):
        if len(front) == 0:
            break
        nb = np.concatenate([ind[ptr[v]:ptr[v + 1]] for v in front.tolist()])
        front = np.unique(nb[~seen[nb]])
        seen[front] = True
    return np.flatnonzero(seen)


def _index_map(size: int, chosen: np.ndarray) -> np.ndarray:
    m = np.full(size, -1, dtype=np.int64)
    m[chosen] = np.arange(len(chosen))
    return m


def _restrict(m, rows, cols, colmap):
    """m[rows][:, cols] renumbered (csr), touching only the entries of ``rows``;
    ``colmap`` (m.shape[1],) the position of each column in ``cols`` or -1."""
    sub = m[rows]
    j = colmap[sub.indices]
    keep = j >= 0
    r = np.repeat(np.arange(len(rows)), np.diff(sub.indptr))
    return sp.csr_matrix((sub.data[keep], (r[keep], j[keep])), shape=(len(rows), len(cols)))


def local_parts(chosen, parts, verts, mmax: int, owner):
    """The map's matrices restricted to the vertices ``verts`` (sorted; ``owner`` the csc
    of parts["rows"]: per vertex its sample-corner rows): returns
    (chosen', parts', coefficient rows R (global indices, sorted)) with the spaces
    V -> verts, V MMAX -> R, sample-corner rows -> those of verts, samples -> theirs."""
    V = parts["rows"].shape[1]
    R = (verts[:, None] * mmax + np.arange(mmax)).ravel()
    Q = np.sort(np.concatenate([owner.indices[owner.indptr[v]:owner.indptr[v + 1]]
                                for v in verts.tolist()]))
    L = np.unique(parts["gather"][Q].indices)
    vm, rm = _index_map(V, verts), _index_map(V * mmax, R)
    qm, lm = _index_map(parts["rows"].shape[0], Q), _index_map(parts["gather"].shape[1], L)
    spaces = {"rows": (Q, verts, vm), "rhs": (R, verts, vm), "cage": (Q, verts, vm),
              "Bu": (Q, R, rm), "gather": (Q, L, lm), "blk": (R, R, rm),
              "Wt": (Q, Q, qm), "Wa": (Q, Q, qm), "Dp": (Q, Q, qm), "Dpp": (Q, Q, qm)}
    out = {k: _restrict(parts[k].tocsr(), *spaces[k]) for k in spaces}
    # the csc matrices: restrict their transposes (csr views) and transpose back
    out["BsT"] = _restrict(parts["BsT"].T, Q, R, rm).T.tocsr()
    out["agg"] = _restrict(parts["agg"].T, Q, L, lm).T.tocsr()
    return _restrict(chosen, R, verts, vm), out, R
