"""Small public accessors and checks nobody else exercises: the package namespace, a GERBS
curve's read-only data, the exact test surfaces' signed distances and the mesh-quality
helpers' input checks.
"""
import numpy as np
import pytest

import gerbs_core
from gerbs_core import ERBS, GERBSBasis, GERBSCurve
from gerbs_core.errors import InvalidParameterError
from gerbs_core.testing.exact import HeightField, Torus, UnitSphere
from gerbs_core.testing.fairness import triangle_normals

KNOTS = np.array([0.0, 0.5, 1.25, 2.0, 2.5, 3.5, 4.0])


def test_package_dir_lists_exactly_the_public_names():
    names = dir(gerbs_core)
    assert names == gerbs_core.__all__ and "BlendingSurface" in names
    for name in names:
        assert getattr(gerbs_core, name) is not None


def test_curve_exposes_its_basis_knots_and_local_curves_read_only():
    L = np.random.default_rng(0).normal(size=(5, 2, 3))
    c = GERBSCurve(KNOTS, L)
    assert isinstance(c.basis, GERBSBasis)
    np.testing.assert_array_equal(c.knots, KNOTS)
    np.testing.assert_array_equal(c.local_curves, L)
    assert not c.local_curves.flags.writeable and not c.knots.flags.writeable
    t = np.linspace(0.6, 3.4, 9)
    np.testing.assert_array_equal(c.basis(t), GERBSBasis(KNOTS)(t))
    # constant local curves are stored with m = 0
    assert GERBSCurve(KNOTS, L[:, 0]).local_curves.shape == (5, 1, 3)


def test_a_kernel_list_with_a_non_kernel_names_its_entry():
    with pytest.raises(InvalidParameterError, match="entry 2 must be a gerbs_core.kernels.Kernel "
                       "or one of") as exc:
        GERBSBasis(KNOTS, [ERBS(), ERBS(), 3, ERBS(), ERBS(), ERBS()])
    assert exc.value.name == "kernel"


@pytest.mark.parametrize("surface, p, d", [
    (UnitSphere(), [[0.0, 0.0, 2.0], [0.5, 0.0, 0.0]], [1.0, -0.5]),
    (Torus(1.0, 0.4), [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.0, 0.1]], [-0.4, 0.6, -0.3]),
])
def test_signed_distances_of_the_exact_surfaces(surface, p, d):
    np.testing.assert_allclose(surface.signed_distance(np.array(p)), d, atol=1e-12)


def test_height_field_signed_distance_on_a_plane():
    flat = HeightField(lambda x, y: [0 * x + 0.25, 0 * x, 0 * x, 0 * x, 0 * x, 0 * x])
    d = flat.signed_distance(np.array([[0.1, 0.2, 1.0], [0.0, 0.0, 0.0]]))
    np.testing.assert_allclose(np.abs(d), [0.75, 0.25], atol=1e-9)
    assert d[0] * d[1] < 0                     # the two sides of the surface


def test_exact_surface_inputs_are_checked():
    with pytest.raises(ValueError, match=r"points must have shape \(N, 3\)"):
        UnitSphere().closest(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="need R > r > 0"):
        Torus(0.3, 0.4)


@pytest.mark.parametrize("points, triangles, text", [
    (np.zeros((3, 2)), [[0, 1, 2]], "points must have shape"),
    (np.zeros((3, 3)), [[0, 1]], "triangles must have shape"),
    (np.zeros((3, 3)), [[0, 1, 3]], "out of range"),
])
def test_mesh_quality_helpers_check_their_input(points, triangles, text):
    with pytest.raises(ValueError, match=text):
        triangle_normals(points, triangles)


def _reviewed_calls():
    """Calls a review of the core as a scipy user found answered by raw numpy errors,
    silently ignored or answered wrongly (each: call, the argument named, message part)."""
    from gerbs_core import GERBSInterpolator
    from gerbs_core.datasets import primitives as prim
    from gerbs_core.mesh.surface import BlendingSurface
    from gerbs_core.mesh.topology import MeshTopology
    from gerbs_core.mesh.validation import validate_geometry
    from gerbs_core.scattered.diagnostics import cover_report
    from gerbs_core.splines.curves import GERBSBasis

    rng = np.random.default_rng(0)
    P = rng.random((50, 2))
    v = np.sin(P[:, 0])
    V, F = prim.cube()
    st = BlendingSurface(V, F).stencil(2)
    pts = st.apply(V)
    return [
        (lambda: GERBSInterpolator(P, v, cover="balls", R=-1.0), "R", "finite and > 0"),
        (lambda: GERBSInterpolator(P, v, cover="balls", R=np.ones(3)), "R", r"shape \(50,\)"),
        (lambda: GERBSInterpolator(P, v, cover="balls", R=np.nan), "R", "finite"),
        (lambda: GERBSInterpolator(P, v, cover="balls", rho=np.zeros(50)), "rho", "> 0"),
        (lambda: GERBSInterpolator(P, v, rho=0.1), "rho", "cover='balls'"),
        (lambda: GERBSInterpolator(P, v, R=0.1), "R", "cover='balls'"),
        (lambda: GERBSInterpolator(P, v, domain=[[0, 0], [1, 0], [1, 1]]), "domain", "voronoi"),
        (lambda: GERBSInterpolator(P, v, fill_value="a"), "fill_value", "real number"),
        (lambda: GERBSInterpolator(P.astype(str), v), "points", "real numbers"),
        (lambda: GERBSInterpolator(P, v.astype(complex)), "values", "real numbers"),
        (lambda: GERBSInterpolator(P, v).memory_estimate(-1), "M", ">= 0"),
        (lambda: GERBSInterpolator(P, v).memory_estimate(10, nu=5), "nu", "max_order = 2"),
        (lambda: cover_report(GERBSInterpolator(P, v), resolution=0), "resolution", ">= 1"),
        (lambda: cover_report(GERBSInterpolator(P, v), samples=np.zeros((4, 3))), "samples",
         r"\(M, 2\)"),
        (lambda: GERBSBasis(["a", "b", "c"]), "knots", "real numbers"),
        (lambda: GERBSBasis([0.0, 1.0, 2.0, 3.0]).support(-1), "j", r"\[0, 2\), got -1"),
        (lambda: GERBSBasis([0.0, 1.0, 2.0, 3.0]).support(99), "j", "got 99"),
        (lambda: MeshTopology(F, 8).face(-1), "f", r"\[0, 6\), got -1"),
        (lambda: MeshTopology(F, 8).one_ring(10), "v", "got 10"),
        (lambda: validate_geometry(V, [[0, 1, 2]]), "topology", "MeshTopology"),
        (lambda: st.apply_moved(pts, np.array([0]), np.zeros((1, 2))), "delta", r"\(3,\)"),
        (lambda: st.apply_moved(pts[:5], np.array([0]), np.zeros((1, 3))), "points", "float64"),
        (lambda: st.apply_moved(pts.tolist(), np.array([0]), np.zeros((1, 3))), "points", "list"),
    ]


@pytest.mark.parametrize("k", range(23))
def test_reviewed_arguments_are_refused_by_name(k):
    from gerbs_core.errors import InvalidParameterError

    call, name, text = _reviewed_calls()[k]
    with pytest.raises(InvalidParameterError, match=text) as exc:
        call()
    assert exc.value.name == name


def test_the_reviewed_checks_keep_what_is_valid():
    """Controls: the same objects with valid arguments answer as before."""
    from gerbs_core import GERBSInterpolator
    from gerbs_core.splines.curves import GERBSBasis

    rng = np.random.default_rng(0)
    P = rng.random((50, 2))
    interp = GERBSInterpolator(P, np.sin(P[:, 0]), fill_value=0)
    assert interp(np.array([[5.0, 5.0]]))[0] == 0.0 and interp.memory_estimate(10) > 0
    balls = GERBSInterpolator(P, np.sin(P[:, 0]), cover="balls", R=0.5)
    assert np.abs(balls(P) - np.sin(P[:, 0])).max() <= 1e-12
    assert GERBSBasis([0.0, 1.0, 2.0, 3.0]).support(np.int64(1)) == (1.0, 3.0)
