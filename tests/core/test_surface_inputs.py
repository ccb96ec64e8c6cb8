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
    (6, np.zeros((2, 2)), "face_index", "out of range"),
    (-1, np.zeros((2, 2)), "face_index", "out of range"),
])
def test_bad_face_points_name_the_argument(cube, face, coords, name, text):
    s = cube[2]
    for f in (s.evaluate, s.partition):
        with pytest.raises(InvalidParameterError, match=text) as exc:
            f(face, coords)
        assert exc.value.name == name


def test_face_index_broadcasts_against_the_points(cube):
    s = cube[2]
    x = np.array([[0.0, 0.0], [0.1, -0.05], [-0.2, 0.1]])
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
