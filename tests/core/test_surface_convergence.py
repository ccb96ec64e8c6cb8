"""Convergence on Franke's F1 over flat Delaunay triangulations.

Vertex data (x, y, F1(x, y)) over a jittered-grid Delaunay triangulation of the
unit square with N = n^2 points; the flat layout is the rest geometry (boundary
keep), so S = (x, y, s(x, y)) and the error is |s - F1| at the
tessellation samples. The full table up to N = 6400 is in scripts/bench_surface.py.
"""
import numpy as np

from gerbs_core.datasets import primitives as P
from gerbs_core.datasets.franke import franke as franke_function
from gerbs_core.mesh.surface import BlendingSurface


def franke(x, y):
    """Franke's F1 (the shared reference implementation)."""
    return franke_function(1, np.stack([x, y], axis=-1))


def franke_errors(n_side, resolution=4, seed=2):
    V, F = P.jittered_patch(n_side, seed)
    X = V.copy()
    X[:, 2] = franke(V[:, 0], V[:, 1])
    s = BlendingSurface(X, F, rest_positions=V, boundary="keep")
    pts, _, _ = s.tessellate(resolution)
    # flat rest layout: the surface's (x, y) are exactly the planar points
    e = np.abs(pts[:, 2] - franke(pts[:, 0], pts[:, 1]))
    return e.max(), np.sqrt(np.mean(e ** 2))


def test_franke_f1_converges_at_order_at_least_two():
    sides = [10, 20, 40]  # N = 100, 400, 1600
    rows = [(1.0 / (n - 1),) + franke_errors(n) for n in sides]
    h, emax, erms = map(np.array, zip(*rows))
    slope_max = np.polyfit(np.log(h), np.log(emax), 1)[0]
    slope_rms = np.polyfit(np.log(h), np.log(erms), 1)[0]
    for n, r in zip(sides, rows):
        print(f"N={n * n:5d} h={r[0]:.4f} max={r[1]:.3e} rms={r[2]:.3e}")
    print(f"observed order: max {slope_max:.2f}, rms {slope_rms:.2f}")
    assert slope_max >= 2.0 and slope_rms >= 2.5
    assert np.all(np.diff(emax) < 0) and np.all(np.diff(erms) < 0)
