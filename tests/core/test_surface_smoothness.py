"""Smoothness of blending surfaces across edges/spokes, measured in one vertex chart.

For every interior half-edge a -> b (a spoke of a's chart, shared by two faces),
S o zeta_a^{-1} is evaluated from each of the two faces at points of the spoke
and its one-sided first and second derivatives (w.r.t. chart coordinates) are
compared analytically (each face's closed-form derivatives pulled back through
its own chart map). Independently, one-sided finite differences (steps 1e-3 and
2.5e-4) across every ray from a vertex to its star boundary's vertices (the
spokes = mesh edges, and the rays to the far corners of quads and n-gons) must
agree up to a truncation error that shrinks with the step. The deliberately
kinked variant (exact polygon gauge) must fail the same checks.
"""
import numpy as np
import pytest

from gerbs_core import primitives as P
from gerbs_core.mesh_surface import BlendingSurface

MESHES = {
    "tri_grid": lambda: P.grid(4, 4, kind="tri"),
    "quad_grid": lambda: P.grid(4, 4),
    "icosphere": lambda: P.icosphere(1),
    "uv_sphere": lambda: P.uv_sphere(8, 6),
    "mixed_bent": lambda: P.mixed_mesh(bend=0.5),
    "delaunay": lambda: P.delaunay_patch(25, 3),
    "wavy_quads": lambda: _wavy(P.grid(4, 4)),
}


def _wavy(mesh):
    V, F = mesh
    V = V.copy()
    V[:, 2] = 0.3 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
    return V, F


def _spokes(s):
    """(a, corner on the start side, corner on the other side, chart point of b)."""
    T, ch = s.topology, s.charts
    for c in np.flatnonzero(T.halfedge_twin >= 0):
        a = T.face_vertices[c]
        c2 = T.corner_next[T.halfedge_twin[c]]
        r, th = ch.unfolded(c, s.shapes.corners[T.corner_next[c]])
        yb = r * np.array([np.cos(ch.scale[a] * th), np.sin(ch.scale[a] * th)])
        yield a, c, c2, yb


def analytic_jumps(s, ts=(0.15, 0.5, 0.85)):
    """Worst relative jumps (first, second derivatives) across all interior spokes."""
    worst = [0.0, 0.0]
    for a, c, c2, yb in _spokes(s):
        y = np.array(ts)[:, None] * yb[None]
        A = s.chart_evaluate(a, y, 2, corner=c)
        B = s.chart_evaluate(a, y, 2, corner=c2)
        L = np.linalg.norm(yb)
        s1 = max(np.abs(A[1]).max(), np.abs(B[1]).max())
        s2 = max(np.abs(A[2]).max(), np.abs(B[2]).max(), s1 / L)
        worst[0] = max(worst[0], np.abs(A[1] - B[1]).max() / s1)
        worst[1] = max(worst[1], np.abs(A[2] - B[2]).max() / s2)
    return worst


def _rays(s):
    """(a, chart point of the ray's end) for the rays from a to every vertex of its star
    boundary (1-ring: the spokes, i.e. mesh edges; far corners: where the exact
    polygon gauge kinks inside quads and n-gons); rays along the border excluded."""
    T, ch = s.topology, s.charts
    for a in range(T.n_vertices):
        star = T.star_corners[T.star_offsets[a]:T.star_offsets[a + 1]]
        for j, c in enumerate(star):
            f = T.corner_face[c]
            n = T.face_sizes[f]
            k = c - T.face_offsets[f]
            far = T.face_offsets[f] + (k + 1 + np.arange(n - 2)) % n  # next(c) .. before prev(c)
            if j == 0 and ch.boundary[a]:
                far = far[1:]
            for q in far:
                r, th = ch.unfolded(c, s.shapes.corners[q])
                yield a, r * np.array([np.cos(ch.scale[a] * th), np.sin(ch.scale[a] * th)])


# one-sided 2nd-order stencils (points 0, h, 2h, 3h)
_D1 = np.array([-3.0, 4.0, -1.0, 0.0]) / 2.0
_D2 = np.array([2.0, -5.0, 4.0, -1.0])


def fd_jumps(s, h=1e-3, ts=(0.3, 0.6)):
    """Worst relative jumps of one-sided finite-difference derivatives (step h) across
    every ray of every chart, first and second order.

    The truncation error is O(h^2) times high derivatives of S, which are large
    (ERBS blending: S is C-infinity but its 4th derivatives reach ~1e3 on these
    meshes), so smoothness shows as jumps that shrink like h^2, kinks as jumps
    that do not shrink.
    """
    worst = [0.0, 0.0]
    for a, yb in _rays(s):
        L = np.linalg.norm(yb)
        n = np.array([-yb[1], yb[0]]) / L  # normal to the ray
        for t in ts:
            k = np.arange(4)[:, None]
            y = np.concatenate([t * yb + k * h * n, t * yb - k * h * n])
            F = s.chart_evaluate(a, y, 0)[0]
            Fp, Fm = F[:4], F[4:]
            d1p, d1m = _D1 @ Fp / h, -(_D1 @ Fm) / h
            d2p, d2m = _D2 @ Fp / h ** 2, _D2 @ Fm / h ** 2
            s1 = max(np.abs(d1p).max(), 1e-300)
            s2 = max(np.abs(d2p).max(), np.abs(d2m).max(), s1 / L)
            worst[0] = max(worst[0], np.abs(d1p - d1m).max() / s1)
            worst[1] = max(worst[1], np.abs(d2p - d2m).max() / s2)
    return worst


@pytest.mark.parametrize("name", sorted(MESHES))
def test_smooth_across_spokes_analytic(name):
    V, F = MESHES[name]()
    for mode in ("regular", "metric"):
        s = BlendingSurface(V, F, mode=mode)
        w = analytic_jumps(s)
        print(f"analytic jumps [{name},{mode}]: C1 {w[0]:.2e}  C2 {w[1]:.2e}")
        assert w[0] <= 1e-5 and w[1] <= 1e-5


@pytest.mark.parametrize("name", ["icosphere", "mixed_bent", "wavy_quads", "uv_sphere"])
def test_finite_differences_converge_across_rays_and_kink_detected(name):
    V, F = MESHES[name]()
    s = BlendingSurface(V, F)
    w1, w2 = fd_jumps(s, 1e-3), fd_jumps(s, 2.5e-4)
    print(f"FD jumps [{name}] h=1e-3: C1 {w1[0]:.2e} C2 {w1[1]:.2e}; h=2.5e-4: C1 {w2[0]:.2e} "
          f"C2 {w2[1]:.2e}")
    # smooth: the one-sided difference quotients differ only by their truncation error,
    # which shrinks with h (pre-asymptotic at these steps: ERBS derivatives are large)
    for a, b in zip(w1, w2):
        assert b <= 1e-5 or b <= a / 3.0
    kinked = BlendingSurface(V, F, exact_gauge=True)
    k1, k2 = fd_jumps(kinked, 1e-3), fd_jumps(kinked, 2.5e-4)
    print(f"kinked [{name}] h=1e-3: C1 {k1[0]:.2e}; h=2.5e-4: C1 {k2[0]:.2e}")
    # kinked: an O(1) jump of the first derivative that does not shrink with h
    assert k1[0] > 1e-2 and k2[0] > 0.8 * k1[0]
    if name != "wavy_quads":  # (regular quad stars are straight across spokes)
        assert analytic_jumps(kinked)[0] > 1e-2
