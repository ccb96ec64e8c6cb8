"""Creases and corners (issue 13 item 1): BlendingSurface(V, F, creases=, corners=).

Full creases cut the surface into a crease curve (normal jump), chains give smooth crease
curves, corners where chains end at the border, meet three or more, or have a vertex
crease of 1; partial weights tighten; interpolation everywhere, C-infinity elsewhere.
"""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.errors import InvalidParameterError
from gerbs_core.mesh.creases import CORNER, crease_cut
from gerbs_core.mesh.surface import BlendingSurface
from gerbs_core.mesh.topology import MeshTopology
from gerbs_core.testing.creases import chain_polyline, normal_jumps, turning_angles

from .test_surface_smoothness import analytic_jumps


def _all_edges(F, V):
    """{(i, j): 1} over every edge of the faces F (input indices)."""
    return {(min(f[k], f[k - 1]), max(f[k], f[k - 1])): 1.0 for f in F for k in range(len(f))}


def _latitude(segments=16, rings=8, ring=2):
    """A UV sphere and the edges (indices into MeshTopology.edges) of one latitude loop."""
    V, F = P.uv_sphere(segments, rings)
    T = MeshTopology(F, len(V))
    loop = 1 + segments * ring + np.arange(segments)
    on = np.isin(T.edges, loop).all(axis=1)
    return V, F, T, np.flatnonzero(on), loop


def _crease_map(T, edges, w=1.0):
    return {tuple(T.edges[e]): w for e in edges}


def _cube_distance(S, lo=-1.0, hi=1.0):
    """Distance of every point to the surface of the box [lo, hi]^3 (points inside or out)."""
    inside = np.minimum(np.abs(S - lo), np.abs(S - hi)).min(axis=1)
    outside = np.linalg.norm(np.maximum(np.maximum(lo - S, S - hi), 0.0), axis=1)
    return np.where(outside > 0, outside, inside)


def test_fully_creased_cube_is_the_cube():
    V, F = P.cube()
    s = BlendingSurface(V, F, creases=_all_edges(F, V))
    S = s.tessellate(8)[0]
    d = _cube_distance(S)
    print(f"fully creased cube: max distance to the cube {d.max():.2e}")
    assert d.max() <= 1e-6
    assert np.abs(s.stencil(8).apply(V) - S).max() <= 1e-12
    # the check catches the uncreased (rounded) cube
    assert _cube_distance(BlendingSurface(V, F).tessellate(8)[0]).max() > 0.05


def test_no_creases_is_the_plain_surface_bit_for_bit():
    V, F = P.suzanne()
    T = MeshTopology(F, len(V))
    plain = BlendingSurface(V, F).tessellate(4)[0]
    zero = BlendingSurface(V, F, creases=_crease_map(T, range(T.n_edges), 0.0),
                           corners=np.zeros(len(V))).tessellate(4)[0]
    assert np.array_equal(plain, zero)


def test_normal_jump_on_the_crease_and_nowhere_else():
    V, F, T, loop_edges, _ = _latitude()
    mask = np.zeros(T.n_edges, bool)
    mask[loop_edges] = True
    r = 16
    creased = BlendingSurface(V, F, creases=_crease_map(T, loop_edges))
    S, tri, _ = creased.tessellate(r)
    on, off = normal_jumps(S, tri, creased.lattice(r), creased.topology, mask)
    smooth = BlendingSurface(V, F)
    S0, tri0, _ = smooth.tessellate(r)
    on0, off0 = normal_jumps(S0, tri0, smooth.lattice(r), smooth.topology, mask)
    print(f"normal jumps (degrees): creased on {on.min():.1f}..{on.max():.1f}, off max "
          f"{off.max():.2f}; smooth on max {on0.max():.2f}, off max {off0.max():.2f}")
    assert on.min() > 10.0 and off.max() < 3.0          # the crease, and nothing else
    assert max(on0.max(), off0.max()) < 3.0              # the same check: no jump at all
    # a jump is O(1), the smooth angles O(h): doubling the resolution halves only the latter
    S2, tri2, _ = creased.tessellate(2 * r)
    on2, off2 = normal_jumps(S2, tri2, creased.lattice(2 * r), creased.topology, mask)
    assert on2.min() > 0.8 * on.min() and off2.max() < 0.7 * off.max()


def _loop_turning(s, loop, r=16):
    idx = chain_polyline(s.lattice(r), s.topology, loop, closed=True)
    S = s.tessellate(r)[0]
    pts = S[np.append(idx, idx[1])]               # wrap once: the turn at the first vertex
    ang = turning_angles(pts)
    at_vertex = np.zeros(len(ang), bool)
    at_vertex[np.arange(r - 1, len(ang), r)] = True  # ang[k] is the turn at pts[k + 1]
    return ang, at_vertex


def test_chain_gives_a_smooth_crease_curve_through_its_vertices():
    V, F, T, loop_edges, loop = _latitude()
    s = BlendingSurface(V, F, creases=_crease_map(T, loop_edges))
    ang, at_vertex = _loop_turning(s, loop)
    S = s.tessellate(16)[0]
    print(f"crease loop turning: at vertices max {ang[at_vertex].max():.3f}, between "
          f"median {np.median(ang[~at_vertex]):.3f} degrees")
    assert np.abs(S[loop] - V[loop]).max() <= 1e-12
    assert ang[at_vertex].max() < 1.5 * np.median(ang[~at_vertex])
    # control: a vertex crease of 1 makes one vertex of the loop a corner, which the same
    # measure sees as a kink
    corners = np.zeros(len(V))
    corners[loop[3]] = 1.0
    k = BlendingSurface(V, F, creases=_crease_map(T, loop_edges), corners=corners)
    ang_k, at_k = _loop_turning(k, loop)
    turn_at = ang_k[np.flatnonzero(at_k)[2]]          # vertex loop[3]
    print(f"vertex crease 1: turning at the corner {turn_at:.2f} degrees")
    assert turn_at > 5.0 * np.median(ang_k[~at_k])


def test_corner_rules():
    V, F = P.cube()
    cube = crease_cut(MeshTopology(F, len(V)), np.ones(12))
    assert cube.corner.all()                                    # 3 creased edges each
    V, F, T, loop_edges, loop = _latitude()
    w = np.zeros(T.n_edges)
    w[loop_edges] = 1.0
    assert not crease_cut(T, w).corner.any()                    # a closed chain
    vw = np.zeros(len(V))
    vw[loop[5]] = 1.0
    cut = crease_cut(T, w, vw)
    assert np.flatnonzero(cut.corner).tolist() == [loop[5]]     # vertex crease 1
    assert (cut.role[cut.copy_of == loop[5]] == CORNER).all()
    # chain ends at the border are corners
    G, GF = P.grid(4, 4)
    GT = MeshTopology(GF, len(G))
    mid = np.flatnonzero(np.isclose(G[GT.edges][:, :, 0], 0.5).all(axis=1))
    w = np.zeros(GT.n_edges)
    w[mid] = 1.0
    cut = crease_cut(GT, w)
    ends = np.flatnonzero(cut.corner)
    assert len(ends) == 2 and GT.vertex_is_boundary[ends].all()
    s = BlendingSurface(G, GF, creases=_crease_map(GT, mid))
    assert np.abs(s.tessellate(4)[0][:len(G)] - G).max() <= 1e-12


def _edge_distance(V, F, edges, w, r=8):
    """Mean distance of the samples on ``edges`` to their straight cage edges."""
    T = MeshTopology(F, len(V))
    s = BlendingSurface(V, F, creases=_crease_map(T, edges, w))
    S = s.tessellate(r)[0]
    p = S[s.lattice(r).edge_samples[edges]]
    a, b = V[T.edges[edges, 0]][:, None], V[T.edges[edges, 1]][:, None]
    t = np.clip(((p - a) * (b - a)).sum(-1) / ((b - a) ** 2).sum(-1), 0, 1)
    return float(np.linalg.norm(p - a - t[..., None] * (b - a), axis=-1).mean())


@pytest.mark.parametrize("case", ["sphere_loop", "cube_edge"])
def test_partial_creases_tighten_monotonically(case):
    if case == "sphere_loop":
        V, F, _, edges, _ = _latitude()
    else:
        V, F = P.cube()
        edges = [0]
    d = [_edge_distance(V, F, edges, w) for w in (0.0, 0.25, 0.5, 0.75, 0.99)]
    print(f"partial creases [{case}]: distance to the cage " + " ".join(f"{x:.5f}" for x in d))
    assert all(b < 0.99 * a for a, b in zip(d, d[1:]))


def test_interpolates_every_vertex_with_creases_and_corners():
    V, F = P.suzanne()
    T = MeshTopology(F, len(V))
    rng = np.random.default_rng(3)
    w = np.where(rng.random(T.n_edges) < 0.15, 1.0, rng.random(T.n_edges) * 0.5)
    corners = np.where(rng.random(len(V)) < 0.1, 1.0, 0.0)
    s = BlendingSurface(V, F, creases=(T.edges, w), corners=corners)
    assert s.model.crease.any_cut
    S = s.tessellate(4)[0]
    assert np.abs(S[:len(V)] - V).max() <= 1e-12
    assert np.isfinite(S).all()
    assert np.abs(s.stencil(4).apply(V) - S).max() <= 1e-9


@pytest.mark.parametrize("mesh", ["sphere_loop", "cube_loop"])
def test_smooth_away_from_creases(mesh):
    """The analytic spoke check of test_surface_smoothness on every spoke not on a crease
    (the interior spokes of the cut mesh), next to the creases too."""
    if mesh == "sphere_loop":
        V, F, T, edges, _ = _latitude(8, 6)
    else:
        V, F = P.cube()
        T = MeshTopology(F, len(V))
        edges = np.flatnonzero(np.isclose(V[T.edges][:, :, 2], 1.0).all(axis=1))  # top loop
    s = BlendingSurface(V, F, creases=_crease_map(T, edges))
    w = analytic_jumps(s)
    print(f"analytic jumps away from creases [{mesh}]: C1 {w[0]:.2e} C2 {w[1]:.2e}")
    assert w[0] <= 1e-5 and w[1] <= 1e-5


def test_creases_map_through_the_repair():
    """Creases on input vertex pairs land on the repaired mesh: an unused vertex in front
    (indices shift) and a cube of separate faces welded by merge_distance."""
    V, F = P.cube()
    ref = BlendingSurface(V, F, creases=_all_edges(F, V)).tessellate(4)[0]
    V1 = np.concatenate([[[5.0, 5.0, 5.0]], V])
    F1 = [tuple(i + 1 for i in f) for f in F]
    s1 = BlendingSurface(V1, F1, creases=_all_edges(F1, V1))
    assert np.abs(s1.tessellate(4)[0] - ref).max() <= 1e-12
    V2 = np.concatenate([V[list(f)] for f in F])
    F2 = [tuple(range(4 * k, 4 * k + 4)) for k in range(len(F))]
    s2 = BlendingSurface(V2, F2, merge_distance=1e-9, creases=_all_edges(F2, V2))
    assert _cube_distance(s2.tessellate(8)[0]).max() <= 1e-6


@pytest.mark.parametrize("creases, corners, name, text", [
    ({(0, 99): 1.0}, None, "creases", "must lie in [0, 7]"),
    ({(0, 6): 1.0}, None, "creases", "(0, 6)] are not edges"),
    ({(0, 1): 1.5}, None, "creases", "[0, 1]"),
    ({(0, 1): float("nan")}, None, "creases", "[0, 1]"),
    ("sharp", None, "creases", "mapping"),
    (([[0, 1]], [1.0, 1.0]), None, "creases", "weights"),
    (None, np.ones(3), "corners", "shape"),
    (None, -np.ones(8), "corners", "[0, 1]"),
])
def test_bad_crease_input_names_the_argument(creases, corners, name, text):
    V, F = P.cube()
    with pytest.raises(InvalidParameterError) as err:
        BlendingSurface(V, F, creases=creases, corners=corners)
    assert name in str(err.value) and text in str(err.value)


def test_the_two_sides_of_every_crease_agree():
    """The tessellation keeps one side's sample on a crease; both sides must give it."""
    from gerbs_core.mesh.lattice import Lattice

    V, F = P.suzanne()
    T = MeshTopology(F, len(V))
    sel = np.random.default_rng(1).random(T.n_edges) < 0.2
    s = BlendingSurface(V, F, creases=(T.edges[sel], np.ones(sel.sum())))
    cut = s.model.crease
    mlat = Lattice(s.model.topology, 8)
    S = s.evaluate(mlat.face, mlat.map_to_polygon(s.layouts.corners))
    m = cut.sample_map(mlat)
    last = np.zeros((s.lattice(8).n_points, 3))
    last[m] = S
    gap = np.abs(S - last[m]).max()
    print(f"{int(cut.cut.sum())} cut edges: sides disagree by {gap:.1e}")
    assert cut.cut.sum() > 50 and gap <= 1e-11


def test_partial_update_of_a_creased_stencil():
    """Stencil.apply_moved (the drag path) on a creased surface: the moved vertices'
    columns come from their copies' columns."""
    V, F, T, edges, loop = _latitude()
    s = BlendingSurface(V, F, creases=_crease_map(T, edges))
    st = s.stencil(4)
    P0 = st.apply(V)
    moved = np.array([loop[2], 0])
    delta = np.array([[0.0, 0.0, 0.1], [0.05, 0.0, 0.0]])
    X1 = V.copy()
    X1[moved] += delta
    pts = P0.copy()
    st.apply_moved(pts, moved, delta)
    assert np.abs(pts - st.apply(X1)).max() <= 1e-12
    assert np.abs(pts - s.with_positions(X1).tessellate(4)[0]).max() <= 1e-12
