"""Shape metrics of gerbs_core.testing (the yardstick of scripts/bench_shape.py):
known answers on exact meshes and surfaces, and negative controls (a dent, a fold,
a flipped triangle, a perturbed second derivative) that each metric must catch."""
import numpy as np
import pytest

from gerbs_core.datasets.primitives import grid, icosphere
from gerbs_core.testing import (
    HeightField,
    Torus,
    UnitSphere,
    box_ratio,
    cotangent_mean_curvature,
    dihedral_angles,
    edge_adjacency,
    fold_counts,
    mean_curvature_from_derivatives,
    mixed_areas,
    observed_order,
    orientation_defects,
    triangle_normals,
    vertex_normals,
)

RNG = np.random.default_rng(11)


def hinge(angle_deg):
    """Two triangles sharing the edge (0,0,0)-(1,0,0); the second turned by angle."""
    a = np.radians(angle_deg)
    P = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -np.cos(a), np.sin(a)]], float)
    return P, np.array([[0, 1, 2], [1, 0, 3]])


def octahedron():
    P = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    T = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return P, np.array(T)


def dented(P, T, depth=0.2):
    """The same mesh with vertex 0 pushed inwards: a dent."""
    Q = P.copy()
    Q[0] *= 1.0 - depth
    return Q, T


def torus_triangles(n_major, n_minor):
    X, Q = Torus(1.0, 0.4).sample(n_major, n_minor)
    return X, np.concatenate([Q[:, [0, 1, 2]], Q[:, [0, 2, 3]]])


# ------------------------------------------------------------------ dihedrals, folds
@pytest.mark.parametrize("angle", [0.0, 1e-4, 30.0, 90.0, 150.0, 179.999])
def test_dihedral_of_a_hinge_is_its_turning_angle(angle):
    P, T = hinge(angle)
    np.testing.assert_allclose(dihedral_angles(P, T), [angle], atol=1e-9)


def test_fold_counts_of_regular_solids():
    P, T = octahedron()  # dihedral angle 109.47: normals differ by 70.53 degrees
    f = fold_counts(P, T)
    assert f["pairs"] == 12 and f["above_60"] == 12 and f["above_90"] == 0
    assert f["max"] == pytest.approx(180 - np.degrees(np.arccos(-1 / 3)), abs=1e-9)
    V, F = icosphere(0)  # icosahedron: normals differ by 41.81 degrees
    f = fold_counts(V, F)
    assert f["above_60"] == 0 and f["max"] == pytest.approx(41.8103149, abs=1e-6)


def test_folds_catch_a_dent_and_a_fold_back():
    V, F = icosphere(3)
    smooth = fold_counts(V, F)
    dent = fold_counts(*dented(V, F, 0.5))
    assert smooth["max"] < 10 and dent["max"] > 2 * smooth["max"]
    P, T = hinge(170.0)  # folded back onto itself: above both thresholds
    f = fold_counts(P, T)
    assert f["above_60"] == 1 and f["above_90"] == 1


def test_adjacency_boundary_and_nonmanifold_edges():
    V, F = grid(3, 3, kind="tri")
    adj = edge_adjacency(F)
    assert len(adj["boundary_edges"]) == 12 and adj["n_nonmanifold"] == 0
    T3 = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])  # three triangles on one edge
    adj3 = edge_adjacency(T3)
    assert adj3["n_nonmanifold"] == 1 and len(adj3["pairs"]) == 0  # no pair is measured there


def test_orientation_defects_catch_a_flipped_triangle():
    V, F = icosphere(2)
    assert orientation_defects(F) == 0
    G = F.copy()
    G[5] = G[5, ::-1]
    assert orientation_defects(G) == 3


# ---------------------------------------------------------------------- normals
def test_vertex_normals_are_radial_on_spheres_and_follow_orientation():
    V, F = icosphere(0)  # symmetric star: exactly radial
    np.testing.assert_allclose(vertex_normals(V, F), V, atol=1e-14)
    V, F = icosphere(3)
    n = vertex_normals(V, F)
    assert np.degrees(np.arccos(np.clip(np.sum(n * V, 1), -1, 1))).max() < 0.5
    np.testing.assert_allclose(vertex_normals(V, F[:, ::-1]), -n, atol=1e-15)
    tn, a = triangle_normals(V, F)
    assert np.all(np.sum(tn * V[F].mean(1), 1) > 0.99) and np.all(a > 0)


def test_vertex_normals_are_angle_weighted():
    """At a cube's corner the angle-weighted normal is the diagonal, whatever the
    triangulation (an unweighted or area-weighted sum depends on the diagonals)."""
    P = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    T = np.array([t for q in quads for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])])
    assert orientation_defects(T) == 0
    n = vertex_normals(P, T)
    c = P - 0.5
    np.testing.assert_allclose(n, c / np.linalg.norm(c, axis=1, keepdims=True), atol=1e-15)


def test_vertex_normals_catch_a_dent():
    V, F = icosphere(3)
    n = vertex_normals(*dented(V, F, 0.3))
    nb = F[np.any(F == 0, axis=1)].ravel()  # the dented vertex's ring
    err = np.degrees(np.arccos(np.clip(np.sum(n * V, 1), -1, 1)))
    assert err[nb].max() > 5.0


# --------------------------------------------------------- cotangent mean curvature
def test_cotangent_curvature_of_spheres_and_planes():
    V, F = icosphere(4)
    H, inner = cotangent_mean_curvature(2.0 * V, F)
    assert inner.all() and np.abs(H - 0.5).max() < 0.01  # radius 2: H = 1/2
    H2, _ = cotangent_mean_curvature(2.0 * V, F[:, ::-1])  # reversed orientation: -H
    np.testing.assert_allclose(H2, -H, rtol=1e-12)
    V, F = grid(5, 5, kind="tri")
    Q = V @ np.linalg.qr(RNG.normal(size=(3, 3)))[0]  # any plane
    H, inner = cotangent_mean_curvature(Q, F)
    assert inner.sum() == 16 and np.all(np.isnan(H[~inner])) and np.abs(H[inner]).max() < 1e-12


def test_cotangent_curvature_catches_a_dent():
    V, F = icosphere(3)
    H, _ = cotangent_mean_curvature(V, F)
    Hd, _ = cotangent_mean_curvature(*dented(V, F, 0.1))
    assert np.abs(H - 1).max() < 0.05 and Hd[0] < 0.0


def test_cotangent_curvature_converges_on_the_torus():
    tor = Torus(1.0, 0.4)
    hs, errs = [], []
    for n in (24, 48, 96):
        X, T = torus_triangles(n, n // 2)
        H, _ = cotangent_mean_curvature(X, T)
        errs.append(np.sqrt(np.mean((H - tor.closest(X)[2]) ** 2)))
        hs.append(1.0 / n)
    assert errs[-1] < 0.02 and observed_order(hs, errs) > 1.5


def test_mixed_areas_of_an_acute_and_an_obtuse_triangle():
    acute = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])
    np.testing.assert_allclose(mixed_areas(acute, [[0, 1, 2]]), np.sqrt(3) / 12, rtol=1e-14)
    obtuse = np.array([[0, 0, 0], [2, 0, 0], [1, 0.2, 0]])  # obtuse at corner 2, area 0.2
    np.testing.assert_allclose(mixed_areas(obtuse, [[0, 1, 2]]), [0.05, 0.05, 0.1], rtol=1e-14)
    V, F = icosphere(2)
    _, a = triangle_normals(V, F)
    A = mixed_areas(V, F)
    assert np.all(A > 0) and A.sum() == pytest.approx(a.sum(), rel=1e-12)


def test_cotangent_curvature_of_obtuse_triangles_uses_mixed_areas():
    """An irregular but exact sampling of the sphere (obtuse triangles everywhere)
    still gives H near 1; with the plain Voronoi area it would not be bounded."""
    from scipy.spatial import ConvexHull
    p = RNG.normal(size=(3000, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    hull = ConvexHull(p)
    T = hull.simplices.copy()
    flip = np.einsum("ij,ij->i", np.cross(p[T[:, 1]] - p[T[:, 0]], p[T[:, 2]] - p[T[:, 0]]),
                     p[T].mean(1)) < 0
    T[flip] = T[flip][:, ::-1]
    H, _ = cotangent_mean_curvature(p, T)
    assert abs(np.median(H) - 1) < 0.05 and np.all(np.isfinite(H))


# ----------------------------------------------------- exact curvature from derivatives
def sphere_param(th, ph):
    st, ct, sp, cp = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
    dS = np.stack([np.stack([ct * cp, -st * sp], -1), np.stack([ct * sp, st * cp], -1),
                   np.stack([-st, 0 * st], -1)], -2)
    d2 = np.zeros(th.shape + (3, 2, 2))
    d2[..., 0, 0, 0], d2[..., 1, 0, 0], d2[..., 2, 0, 0] = -st * cp, -st * sp, -ct
    d2[..., 0, 0, 1] = d2[..., 0, 1, 0] = -ct * sp
    d2[..., 1, 0, 1] = d2[..., 1, 1, 0] = ct * cp
    d2[..., 0, 1, 1], d2[..., 1, 1, 1] = -st * cp, -st * sp
    return dS, d2


def test_exact_mean_curvature_of_sphere_and_cylinder():
    th, ph = RNG.uniform(0.2, 3.0, 50), RNG.uniform(0, 6.2, 50)
    dS, d2 = sphere_param(th, ph)
    np.testing.assert_allclose(mean_curvature_from_derivatives(dS, d2), 1.0, rtol=1e-12)
    # swapping the parameters reverses the orientation: H = -1
    sw = mean_curvature_from_derivatives(dS[..., ::-1], d2[..., ::-1, ::-1])
    np.testing.assert_allclose(sw, -1.0, rtol=1e-12)
    a, u = 0.7, RNG.uniform(0, 6, 20)  # cylinder (a cos u, a sin u, v), outward
    dS = np.zeros((20, 3, 2))
    dS[:, 0, 0], dS[:, 1, 0], dS[:, 2, 1] = -a * np.sin(u), a * np.cos(u), 1.0
    d2 = np.zeros((20, 3, 2, 2))
    d2[:, 0, 0, 0], d2[:, 1, 0, 0] = -a * np.cos(u), -a * np.sin(u)
    np.testing.assert_allclose(mean_curvature_from_derivatives(dS, d2), 1 / (2 * a), rtol=1e-12)


def test_exact_mean_curvature_catches_a_perturbed_second_derivative():
    th, ph = RNG.uniform(0.2, 3.0, 50), RNG.uniform(0, 6.2, 50)
    dS, d2 = sphere_param(th, ph)
    bad = d2 + 0.05 * RNG.normal(size=d2.shape)
    assert np.abs(mean_curvature_from_derivatives(dS, bad) - 1).max() > 0.01


def test_exact_mean_curvature_of_a_graph_matches_the_height_field():
    hf = HeightField.wave()
    x, y = RNG.uniform(-1, 1, (2, 200))
    f, fx, fy, fxx, fxy, fyy = hf.jet(x, y)
    dS = np.zeros((200, 3, 2))
    dS[:, 0, 0] = dS[:, 1, 1] = 1.0
    dS[:, 2, 0], dS[:, 2, 1] = fx, fy
    d2 = np.zeros((200, 3, 2, 2))
    d2[:, 2, 0, 0], d2[:, 2, 0, 1], d2[:, 2, 1, 0], d2[:, 2, 1, 1] = fxx, fxy, fxy, fyy
    H = mean_curvature_from_derivatives(dS, d2)
    d, n, Hf = hf.closest(np.stack([x, y, f], -1))
    np.testing.assert_allclose(H, Hf, rtol=1e-12, atol=1e-14)
    assert np.abs(d).max() < 1e-14 and np.ptp(H) > 0.5  # non-trivial curvature


# ------------------------------------------------------------------ exact surfaces
def test_sphere_and_torus_distances_normals_curvatures():
    n = RNG.normal(size=(100, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = RNG.uniform(-0.3, 0.3, 100)
    dd, nn, H = UnitSphere().closest(n * (1 + d)[:, None])
    np.testing.assert_allclose(dd, d, atol=1e-15)
    np.testing.assert_allclose(nn, n, atol=1e-15)
    tor = Torus(1.0, 0.4)
    X, _ = tor.sample(16, 12, phase=0.3)
    d0, n0, H0 = tor.closest(X)
    assert np.abs(d0).max() < 1e-15
    dd, nn, H1 = tor.closest(X + 0.2 * n0)  # moved along the normal
    np.testing.assert_allclose(dd, 0.2, atol=1e-14)
    np.testing.assert_allclose(nn, n0, atol=1e-14)
    np.testing.assert_allclose(H1, H0, atol=1e-13)
    _, _, Hq = tor.closest(np.array([[1.4, 0, 0], [0, 0.6, 0], [1.0, 0, 0.4]]))
    np.testing.assert_allclose(Hq, [(1 / 0.4 + 1 / 1.4) / 2, (1 / 0.4 - 1 / 0.6) / 2, 1 / 0.8])


def test_height_field_projection_and_known_curvature():
    def paraboloid(x, y):  # z = -(x^2 + y^2) / 2: H = 1 at the top (upward normal)
        return -(x * x + y * y) / 2, -x, -y, -np.ones_like(x), 0 * x, -np.ones_like(x)
    hf = HeightField(paraboloid)
    d, n, H = hf.closest(np.array([[0.0, 0.0, 0.1], [0.0, 0.0, -0.2]]))
    np.testing.assert_allclose(d, [0.1, -0.2], atol=1e-15)
    np.testing.assert_allclose(H, 1.0)
    np.testing.assert_allclose(n, [[0, 0, 1], [0, 0, 1]], atol=1e-15)
    hw = HeightField.wave()
    x, y = RNG.uniform(-1, 1, (2, 300))
    q = np.stack([x, y, hw.height(x, y)], -1)
    _, n0, H0 = hw.closest(q)
    off = RNG.uniform(-0.1, 0.1, 300)
    dd, nn, H1 = hw.closest(q + off[:, None] * n0)
    np.testing.assert_allclose(dd, off, atol=1e-12)
    np.testing.assert_allclose(H1, H0, atol=1e-10)


def test_cotangent_curvature_agrees_with_the_height_field():
    hw = HeightField.wave()
    V, F = grid(60, 60, kind="tri", size=2.0)
    V = V - V.mean(0)
    V[:, 2] = hw.height(V[:, 0], V[:, 1])
    H, inner = cotangent_mean_curvature(V, F)
    Hx = hw.closest(V)[2]
    assert np.sqrt(np.mean((H - Hx)[inner] ** 2)) < 0.02 * np.abs(Hx).max()


# ------------------------------------------------------------------- box, orders
def test_box_ratio():
    V, _ = icosphere(2)
    np.testing.assert_allclose(box_ratio(V * [1.5, 1, 0.5], V), [1.5, 1, 0.5], rtol=1e-12)
    flat = V * [1, 1, 0]
    r = box_ratio(V, flat)
    assert np.isnan(r[2]) and r[0] == pytest.approx(1.0)


def test_observed_order():
    h = np.array([0.4, 0.2, 0.1, 0.05])
    assert observed_order(h, 3 * h ** 2) == pytest.approx(2.0, abs=1e-12)
    assert observed_order(h, h) == pytest.approx(1.0, abs=1e-12)
    assert observed_order(h, 5 * h ** 0.5 * (1 + 0.01 * RNG.normal(size=4))) < 0.6
    assert np.isnan(observed_order(h, [1, 0, 1, 1]))
    with pytest.raises(ValueError):
        observed_order([0.1], [1.0])
