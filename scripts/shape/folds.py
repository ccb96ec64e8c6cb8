"""Where a GERBS surface folds: the output pairs above a dihedral threshold, by cage face
and nearest vertex, with the star's valence, anisotropy and agreement energy.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/shape/folds.py [suzanne|cow|file.obj]
        [--resolution 8] [--threshold 90] [--top 15] [--exact]

A diagnostic for the fair-shape rule (gerbs_core.mesh.agreement), not a benchmark:
``fold_sites(surface, r, t)`` is importable; ``vertex_agreement(surface)`` gives each
vertex's share of the agreement energy sum_p sum_k Psi_k |l_k(p) - S(p)|^2 (which
equals the pairwise sum_{k<j} Psi_k Psi_j |l_k - l_j|^2 at every sample) over its own
rows, divided by h_v^2 (the star's mean ring-1 distance) so that it is scale-free.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

import numpy as np  # noqa: E402

from gerbs_core.testing import dihedral_angles, edge_adjacency  # noqa: E402


def load(name: str):
    """(V, F) of suzanne, cow (MeshLab's sample) or an OBJ file."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from shape.inputs import REAL, load_real
    if name in REAL:
        return load_real(name, [])
    from gerbs_core.datasets.obj import read_obj
    V, F = read_obj(name)
    return np.asarray(V, dtype=np.float64), F


def star_stats(topo, X):
    """(valence (V,), anisotropy (V,): longest / shortest edge at the vertex)."""
    e = np.asarray(topo.edges)
    ln = np.linalg.norm(X[e[:, 0]] - X[e[:, 1]], axis=1)
    V = len(X)
    lo, hi = np.full(V, np.inf), np.zeros(V)
    for k in (0, 1):
        np.minimum.at(lo, e[:, k], ln)
        np.maximum.at(hi, e[:, k], ln)
    val = np.bincount(e.ravel(), minlength=V)
    return val, hi / lo


def vertex_agreement(s, resolution=None):
    """(V,) every vertex's agreement energy over its rows / h_v^2 (module docstring), on the
    energies' sample lattice (default: the default rule's resolution)."""
    from gerbs_core.mesh.agreement import FairnessRule, _samples, face_sharpness
    resolution = FairnessRule().resolution if resolution is None else resolution
    from gerbs_core.mesh.rings import data_rings
    m = s.model
    topo, corners = m.topology, s.layouts.corners
    rings = data_rings(topo, m.charts, corners)
    sharp = face_sharpness(topo, s.vertices, 50.0, 80.0)
    smp = _samples(topo, m.charts, corners, m.cover, rings.h, resolution, sharp)
    coef = s.coefficients.reshape(topo.n_vertices, -1, 3)
    M = coef.shape[1]
    l = s.vertices[smp.vertex] + np.einsum("rm,rmk->rk", smp.Bu[:, :M], coef[smp.vertex])
    S = np.stack([np.bincount(smp.sample, smp.psi * l[:, k], minlength=smp.n_samples)
                  for k in range(3)], 1)
    # rows with Psi = 1 were dropped (there every other Psi is 0 and the energy 0): the
    # mean over the live rows of a sample, weighted by their Psi
    Pt = np.bincount(smp.sample, smp.psi, minlength=smp.n_samples)
    e = smp.psi * ((l - S[smp.sample] / np.maximum(Pt, 1e-300)[smp.sample, None]) ** 2).sum(1)
    E = np.bincount(smp.vertex, e * smp.weight, minlength=topo.n_vertices)
    return E / rings.h ** 2


def _pairs(s, r, threshold):
    """(lattice, P, T, adjacency, indices of the pairs above ``threshold``) at resolution r."""
    lat = s.lattice(r)
    P, T, _ = s.tessellate(r)
    T = np.asarray(T)
    adj = edge_adjacency(T)
    ang = dihedral_angles(P, T, adj)
    return lat, P, T, adj, ang, np.flatnonzero(ang > threshold)


def fold_sites(s, r=8, threshold=90.0):
    """Output pairs above ``threshold`` degrees: list of (angle, face, nearest face corner
    vertex, distance to it / the face's mean edge, the other triangle's face)."""
    lat, P, T, adj, ang, ks = _pairs(s, r, threshold)
    tf = np.asarray(lat.triangle_face)
    topo = s.topology
    out = []
    for k in ks:
        i, j = adj["pairs"][k]
        mid = P[adj["pair_edges"][k]].mean(0)
        f = tf[i]
        vs = topo.face_vertices[topo.face_offsets[f]:topo.face_offsets[f + 1]]
        d = np.linalg.norm(s.vertices[vs] - mid, axis=1)
        el = np.linalg.norm(s.vertices[vs] - s.vertices[np.roll(vs, -1)], axis=1).mean()
        out.append((float(ang[k]), int(f), int(vs[np.argmin(d)]), float(d.min() / el),
                    int(tf[j])))
    return out


def _unit(a):
    return a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-300)


def turned_corners(s):
    """(C,) cos of the angle between each corner's vertex tangent plane (the normal of l_v's
    linear part) and its face's rest normal (Newell), and (C,) the same for the vertex's
    area-weighted mean normal."""
    topo, X = s.topology, s.vertices
    fv, nxt = np.asarray(topo.face_vertices), np.asarray(topo.corner_next)
    cf = np.asarray(topo.corner_face)
    nf = np.zeros((topo.n_faces, 3))
    np.add.at(nf, cf, np.cross(X[fv], X[fv[nxt]]))
    nf = _unit(nf)
    coef = s.coefficients.reshape(topo.n_vertices, -1, 3)
    nv = _unit(np.cross(coef[:, 0], coef[:, 1]))
    A = np.cross(X[fv[nxt]] - X[fv], X[fv[np.asarray(topo.corner_prev)]] - X[fv])
    nm = np.zeros((topo.n_vertices, 3))
    np.add.at(nm, fv, A)
    nm = _unit(nm)
    return (np.einsum("ij,ij->i", nv[fv], nf[cf]), np.einsum("ij,ij->i", nm[fv], nf[cf]))


def turned_candidates(s):
    """For every corner whose vertex tangent plane is turned more than 90 degrees against
    its face (:func:`turned_corners`): (corner, angles (K,) in degrees between each
    candidate fit's tangent plane at the rest shape and the face's rest normal, candidate
    labels "d<degree>" in the choice's order, base candidates then the spread stars')."""
    from gerbs_core.mesh.agreement import FairnessRule
    from gerbs_core.mesh.fits import candidate_fits_all
    from gerbs_core.mesh.rings import data_rings
    from gerbs_core.mesh.row_values import candidate_coefs
    from gerbs_core.mesh.spread_fits import spread_candidates
    m, X, rule = s.model, s.vertices, FairnessRule()
    topo, corners = m.topology, s.layouts.corners
    rings = data_rings(topo, m.charts, corners)
    cands = candidate_fits_all(rings, rule.candidates)
    cands = cands + spread_candidates(topo, m.charts, corners, rings, X, rule.spread)[0]
    V = topo.n_vertices
    lin = [c.reshape(V, -1, 3)[:, :2] for c in candidate_coefs(cands, X)]
    fv, cf, nxt = (np.asarray(a) for a in (topo.face_vertices, topo.corner_face,
                                            topo.corner_next))
    nf = np.zeros((topo.n_faces, 3))
    np.add.at(nf, cf, np.cross(X[fv], X[fv[nxt]]))
    nf = _unit(nf)
    out = []
    for c in np.flatnonzero(turned_corners(s)[0] < 0):
        n = _unit(np.stack([np.cross(L[fv[c], 0], L[fv[c], 1]) for L in lin]))
        out.append((int(c), np.degrees(np.arccos(np.clip(n @ nf[cf[c]], -1, 1)))))
    return out, [f"d{c.degree}" for c in cands]


def exact_split(s, r=8, threshold=90.0):
    """The pairs above ``threshold`` split by what the exact surface does there: (n pairs,
    n whose exact normals at the two triangles' centroids differ by more than 60 degrees
    (the surface turns, not its sampling), n with a triangle more than 45 degrees off the
    exact normal at its centroid, n in a face with a corner whose vertex tangent plane is
    turned more than 90 degrees against the face, n of those corners where the mean
    normal is turned too, corners turned)."""
    lat, P, T, adj, ang, ks = _pairs(s, r, threshold)
    tf = np.asarray(lat.triangle_face)
    _, _, _, local = lat.polygons(quads=False)
    xl = lat.map_to_polygon(s.layouts.corners, local=True)
    pairs = adj["pairs"][ks]
    tris = np.unique(pairs.ravel())
    xc = xl[np.asarray(local)].reshape(-1, 3, 2)[tris].mean(1)
    dS = s.evaluate(tf[tris], xc, 1)
    ne = np.zeros((len(T), 3))
    ne[tris] = _unit(np.cross(dS[..., 0], dS[..., 1]))
    p = P[T]
    nt = _unit(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))
    i, j = pairs.T
    turn = np.einsum("ij,ij->i", ne[i], ne[j]) < 0.5
    off = np.minimum(np.einsum("ij,ij->i", ne[i], nt[i]), np.einsum("ij,ij->i", ne[j], nt[j]))
    cos_fit, cos_mean = turned_corners(s)
    bad = cos_fit < 0
    face_bad = np.zeros(s.topology.n_faces, bool)
    face_bad[np.asarray(s.topology.corner_face)[bad]] = True
    in_bad = face_bad[tf[i]] | face_bad[tf[j]]
    return (len(ks), int(turn.sum()), int((off < np.cos(np.pi / 4)).sum()), int(in_bad.sum()),
            int((cos_mean[bad] < 0).sum()), int(bad.sum()))


def report(s, r, threshold, top):
    sites = fold_sites(s, r, threshold)
    topo = s.topology
    val, an = star_stats(topo, s.vertices)
    E = vertex_agreement(s)
    print(f"{len(sites)} pairs above {threshold} deg; vertices: median agreement "
          f"{np.median(E):.3g}, 95% {np.percentile(E, 95):.3g}; median anisotropy "
          f"{np.median(an):.2f}")
    byv = {}
    for a, f, v, d, f2 in sites:
        byv.setdefault(v, []).append((a, f, d, f2))
    rank = np.argsort(-E)
    pos = np.empty_like(rank)
    pos[rank] = np.arange(len(E))
    print("vertex | pairs | largest | faces | dist/edge | valence | aniso | degree | E | E rank | "
          "(corner, degree, aniso) of the faces")
    for v, lst in sorted(byv.items(), key=lambda kv: -len(kv[1]))[:top]:
        fs = sorted({x[1] for x in lst} | {x[3] for x in lst})
        corners = sorted(set(np.concatenate([topo.face_vertices[topo.face_offsets[f]:
                                                                topo.face_offsets[f + 1]]
                                             for f in fs]).tolist()))
        info = [(c, int(s.degrees[c]), round(float(an[c]), 1)) for c in corners]
        print(f"{v} | {len(lst)} | {max(x[0] for x in lst):.0f} | {fs} | "
              f"{np.mean([x[2] for x in lst]):.2f} | {val[v]} | {an[v]:.1f} | {s.degrees[v]} | "
              f"{E[v]:.3g} | {pos[v]} | {info}")
    return sites, E


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh", nargs="?", default="suzanne")
    ap.add_argument("--resolution", type=int, default=8)
    ap.add_argument("--threshold", type=float, default=90.0)
    ap.add_argument("--top", type=int, default=15)
    ap.add_argument("--exact", action="store_true", help="also split the pairs by the exact "
                    "surface (exact_split)")
    a = ap.parse_args()
    from gerbs_core import BlendingSurface
    V, F = load(a.mesh)
    s = BlendingSurface(V, F)
    report(s, a.resolution, a.threshold, a.top)
    if a.exact:
        n, turn, off, in_bad, mean_bad, bad = exact_split(s, a.resolution, a.threshold)
        print(f"of {n} pairs: {turn} where the exact normals at the two triangles' centroids "
              f"differ by > 60 deg (the surface turns), {off} with a triangle > 45 deg off the "
              f"exact normal at its centroid; {in_bad} in a face with a corner whose vertex "
              f"tangent plane is turned > 90 deg against the face ({bad} such corners, the "
              f"area-weighted mean normal turned too at {mean_bad})")
        rows, labels = turned_candidates(s)
        print(f"at {sum(bool((a < 90).any()) for _, a in rows)} of those {len(rows)} corners "
              f"some candidate fit's tangent plane is within 90 deg of the face; corner, "
              f"vertex, chosen degree, candidates' angles ({' '.join(labels)}):")
        for c, a in rows:
            v = int(s.topology.face_vertices[c])
            print(f"  {c} | {v} | {s.degrees[v]} | {' '.join(f'{x:.0f}' for x in a)}")


if __name__ == "__main__":
    main()
