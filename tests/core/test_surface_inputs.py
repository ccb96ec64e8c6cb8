"""BlendingSurface's settings and evaluation inputs (gerbs_core.mesh.surface_inputs), its
read-only data (boundary rule, coefficients) and the crease input's forms
(gerbs_core.mesh.crease_surface): every bad value raises InvalidParameterError naming the
argument; the accepted forms give the surface they describe.
"""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.errors import InvalidParameterError
from gerbs_core.mesh.surface import BlendingSurface
from gerbs_core.mesh.topology import MeshTopology


@pytest.fixture(scope="module")
def cube():
    V, F = P.cube()
    return V, F, BlendingSurface(V, F)


@pytest.mark.parametrize("kw, name", [
    (dict(shrink=0.0), "shrink"), (dict(shrink=1.5), "shrink"), (dict(shrink="1"), "shrink"),
    (dict(kappa=1.0), "kappa"), (dict(kappa=0.0), "kappa"), (dict(kappa=None), "kappa"),
    (dict(fairness="fair"), "fairness"),
])
def test_bad_settings_name_the_argument(kw, name):
    V, F = P.cube()
    with pytest.raises(InvalidParameterError) as exc:
        BlendingSurface(V, F, **kw)
    assert exc.value.name == name


@pytest.mark.parametrize("face, coords, name, text", [
    (0, np.zeros((4, 3)), "local_coords", "shape"),
    (0, [[0.0, np.nan]], "local_coords", "finite"),
    ([0, 1, 2], np.zeros((2, 2)), "face_index", "broadcast"),
    (0.5, np.zeros((2, 2)), "face_index", "integers"),
    (6, np.zeros((2, 2)), "face_index", r"must lie in \[0, 6\), got \[6, 6\]"),
    (-1, np.zeros((2, 2)), "face_index", r"must lie in \[0, 6\), got \[-1, -1\]"),
    (0, [["a", "b"]], "local_coords", "real numbers"),
    # the cube's face 0 is the square [0, 2]^2 in its layout: outside it the surface is
    # not defined (found by a review: [3, 1] extrapolated silently, [5, 5] blamed the
    # kernel, partition gave NaN at [50, 0.2])
    (0, [[3.0, 1.0]], "local_coords", "outside their faces"),
    (0, [[1.0, 1.0], [5.0, 5.0]], "local_coords", r"first indices \[1\]"),
    (0, [[50.0, 0.2]], "local_coords", "outside their faces"),
])
def test_bad_face_points_name_the_argument(cube, face, coords, name, text):
    s = cube[2]
    for f in (s.evaluate, s.partition):
        with pytest.raises(InvalidParameterError, match=text) as exc:
            f(face, coords)
        assert exc.value.name == name


def test_face_index_broadcasts_against_the_points(cube):
    s = cube[2]
    x = np.array([[0.0, 0.0], [0.1, 0.05], [0.2, 0.1]])
    one = s.evaluate(2, x)
    assert one.shape == (3, 3)
    np.testing.assert_array_equal(one, s.evaluate(np.full(3, 2), x))


@pytest.mark.parametrize("rule", ["keep", "straighten"])
def test_boundary_rule_is_reported(rule):
    V, F = P.grid(3)
    assert BlendingSurface(V, F, boundary=rule).boundary == rule


def test_coefficients_are_read_only_and_linear_in_the_positions(cube):
    """The local functions' coefficients are a fixed linear map of the positions (the fits'
    operator): doubling the positions doubles them, translating leaves them (the constant
    term is the vertex itself)."""
    V, F, s = cube
    C = s.coefficients
    assert C.shape[0] == len(V) and C.shape[2] == 3
    assert not C.flags.writeable
    with pytest.raises(ValueError):
        C[0, 0, 0] = 1.0
    assert np.abs(C).max() > 0.1
    np.testing.assert_allclose(s.with_positions(2.0 * V).coefficients, 2.0 * C, atol=1e-12)
    np.testing.assert_allclose(s.with_positions(V + [3.0, -1.0, 2.0]).coefficients, C,
                               atol=1e-12)


# ------------------------------------------------------------------ crease input forms

def test_empty_crease_mapping_is_no_crease(cube):
    V, F, plain = cube
    s = BlendingSurface(V, F, creases={})
    assert s.model.crease is None
    np.testing.assert_array_equal(s.tessellate(3)[0], plain.tessellate(3)[0])


def test_creases_on_a_topology_input_are_those_of_the_face_list():
    V, F = P.cube()
    creases = {(int(a), int(b)): 1.0 for a, b in MeshTopology(F, len(V)).edges[:4]}
    ref = BlendingSurface(V, F, creases=creases).tessellate(4)[0]
    s = BlendingSurface(V, MeshTopology(F, len(V)), creases=creases)
    assert s.model.crease is not None
    np.testing.assert_array_equal(s.tessellate(4)[0], ref)


@pytest.mark.parametrize("creases, corners, name, text", [
    ({(0, 1.5): 1.0}, None, "creases", "integers"),
    ({("a", "b"): 1.0}, None, "creases", "vertex index pairs"),
    ({(0, 1): "sharp"}, None, "creases", "weights numbers"),
    (None, ["x"] * 8, "corners", "8 vertex weights"),
])
def test_malformed_crease_input_names_the_argument(creases, corners, name, text):
    V, F = P.cube()
    with pytest.raises(InvalidParameterError, match=text) as exc:
        BlendingSurface(V, F, creases=creases, corners=corners)
    assert exc.value.name == name


def test_points_on_the_faces_edges_and_corners_are_inside(cube):
    """The outside check's tolerance: every lattice point of every face (edges and corners
    included, as map_to_polygon computes them) is accepted; a point 1e-6 of the face's size
    beyond an edge is not."""
    s = cube[2]
    lat = s.lattice(4)
    x = lat.map_to_polygon(s.layouts.corners)
    assert s.evaluate(lat.face, x).shape == (lat.n_points, 3)
    with pytest.raises(InvalidParameterError, match="outside"):
        s.evaluate(0, [[1.0, -2e-6]])
    assert s.evaluate(0, [[1.0, -1e-12]]).shape == (1, 3)


@pytest.mark.parametrize("call, name, text", [
    (lambda s: s.evaluate(0, [1.0, 1.0], nu=1.0), "nu", "integer, got 1.0"),
    (lambda s: s.evaluate(0, [1.0, 1.0], nu=np.float64(1)), "nu", "integer"),
    (lambda s: s.evaluate(0, [1.0, 1.0], nu=3), "nu", "max_order = 2"),
    (lambda s: s.partition(0, [1.0, 1.0], nu=5), "nu", "max_order = 1"),
    (lambda s: s.local_function(0, [0.1, 0.2], nu=7), "nu", "max_order = 2"),
    (lambda s: s.local_function(-1, [0.1, 0.2]), "v", r"\[0, 8\), got -1"),
    (lambda s: s.local_function(99, [0.1, 0.2]), "v", "got 99"),
    (lambda s: s.local_function(1.5, [0.1, 0.2]), "v", "got 1.5"),
    (lambda s: s.local_function(0, [0.1, 0.2, 0.3]), "y", r"shape \(1, 3\)"),
    (lambda s: s.local_function(0, [[np.nan, 0.0]]), "y", "finite"),
    (lambda s: s.chart_evaluate(-1, [0.1, 0.1]), "v", "got -1"),
    (lambda s: s.chart_evaluate(0, [0.1, 0.1], corner=99), "corner", "star"),
    # beyond the star the surface is not defined; the error names y, not an internal face
    (lambda s: s.chart_evaluate(0, [50.0, 50.0]), "y", "outside its star"),
])
def test_bad_derivative_orders_vertices_and_chart_points_name_the_argument(cube, call, name, text):
    """Found by a review: nu=1.0 crashed with a raw TypeError, local_function(-1) wrapped
    to the last vertex and dropped a third coordinate silently, nu=7 was accepted."""
    with pytest.raises(InvalidParameterError, match=text) as exc:
        call(cube[2])
    assert exc.value.name == name


def test_surfaces_and_stencils_are_immutable(cube):
    """Attribute writes after construction raise (a review set S.kernel = 'affine': the
    surface then reported another kernel than it used); the lazy caches still work."""
    s = cube[2]
    for obj, attr in ((s, "kernel"), (s, "memory_budget"), (s, "new_name")):
        with pytest.raises(AttributeError, match="immutable"):
            setattr(obj, attr, 1)
    st = s.stencil(2)
    with pytest.raises(AttributeError, match="immutable"):
        st.base = None
    with pytest.raises(AttributeError, match="immutable"):
        del st.fits
    X = s.vertices
    P = st.apply(X)
    moved = P.copy()
    st.apply_moved(moved, np.array([0]), np.array([[0.1, 0.0, 0.0]]))   # fills the caches
    X2 = X.copy()
    X2[0, 0] += 0.1
    assert np.abs(moved - st.apply(X2)).max() <= 1e-12
    assert np.abs(s.with_positions(X2).tessellate(2)[0] - st.apply(X2)).max() <= 1e-12
