"""gerbs_core.testing.stripe_components (zebra stripes as a number): the known answer on a
sphere, bumps and noise caught, what is not counted, and its errors."""
import numpy as np
import pytest

from gerbs_core.datasets.primitives import icosphere
from gerbs_core.errors import InvalidParameterError
from gerbs_core.testing import sphere_directions, stripe_components


def bumped(V, amp, seed=5, n=6):
    """The unit sphere's points pushed out by ``n`` Gaussian bumps of height ``amp``."""
    rng = np.random.default_rng(seed)
    c = rng.normal(size=(n, 3))
    c /= np.linalg.norm(c, axis=1, keepdims=True)
    bump = sum(np.exp(-np.sum((V - ci) ** 2, axis=1) / 0.02) for ci in c)
    return V * (1.0 + amp * bump)[:, None]


def test_directions_are_unit_and_spread():
    D = sphere_directions(24)
    assert np.allclose(np.linalg.norm(D, axis=1), 1.0)
    assert np.linalg.norm(D.mean(axis=0)) < 0.05          # no hemisphere favoured
    # every pair apart: the closest pair of 24 even points is ~40 degrees apart
    G = D @ D.T - 2 * np.eye(24)
    assert np.degrees(np.arccos(G.max())) > 30


@pytest.mark.parametrize("stripes, pieces", [(18.0, 18.0), (9.0, 10.0), (5.0, 6.0)])
def test_a_sphere_has_one_piece_per_band(stripes, pieces):
    """Bands b = floor(s asin(n.a) / pi): two caps and rings, each connected on a fine
    sphere, for every axis (s = 18: the -9th to the 8th; the 9th is the pole alone)."""
    V, F = icosphere(4)
    assert stripe_components(V, F, stripes=stripes) == pieces
    assert stripe_components(V, F, V, stripes=stripes) == pieces       # exact normals
    assert stripe_components(V, F, stripes=stripes, min_area=0.0) == pieces


def test_bumps_add_pieces_and_specks_are_not_counted():
    V, F = icosphere(4)
    # bumps steep enough to make their own extremum of n.a ring themselves with a stripe
    assert stripe_components(bumped(V, 0.05), F) > 20
    assert stripe_components(bumped(V, 0.1), F) > stripe_components(bumped(V, 0.05), F) + 5
    # gentle ones do not (a zebra rendering shows no island either)
    assert stripe_components(bumped(V, 0.02), F) == 18.0
    # noise of 0.13 edges (normals off by ~8 degrees) frays the stripes everywhere; most
    # of its pieces are specks of a few vertices, left out at the default min_area
    rng = np.random.default_rng(1)
    W = V * (1 + 1e-2 * rng.normal(size=len(V)))[:, None]
    every, visible = stripe_components(W, F, min_area=0.0), stripe_components(W, F)
    assert visible > 60 and every > 2 * visible


def test_scale_and_translation_do_not_matter_and_bad_points_are_not_counted():
    V, F = icosphere(3)
    W = bumped(V, 0.1)
    base = stripe_components(W, F)
    assert stripe_components(7.0 * W + 1.0, F) == base
    assert stripe_components(np.vstack([W, [[5.0, 5.0, 5.0]]]), F) == base  # in no triangle
    N = np.array(W)
    N[:] = np.nan                                              # no finite normal: nothing
    assert stripe_components(W, F, N) == 0.0
    # a NaN position: its zero vertex normal is not read as a normal in band 0
    U = np.array(V)
    U[5] = np.nan
    assert stripe_components(U, F, stripes=9.0) == stripe_components(V, F, stripes=9.0)
    assert stripe_components(V, np.zeros((0, 3), dtype=int)) == 0.0     # no triangles


def _turning(a, d):
    """A rotation (3, 3) taking unit vector a to unit vector d (Rodrigues)."""
    v, c = np.cross(a, d), float(np.dot(a, d))
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def test_the_figure_is_the_mean_over_the_directions():
    """Turning the mesh so that each of the 24 directions becomes the single direction of
    directions=1, and averaging those counts, gives the 24-direction figure."""
    V, F = icosphere(3)
    W = bumped(V, 0.1)
    (d,) = sphere_directions(1)
    one = [stripe_components(W @ _turning(a, d).T, F, directions=1) for a in sphere_directions(24)]
    assert len(set(one)) > 1                                   # the directions differ here
    assert np.mean(one) == pytest.approx(stripe_components(W, F), abs=0.1)


def test_given_normals_of_any_length_count_as_their_directions():
    V, F = icosphere(3)
    W = bumped(V, 0.1)
    from gerbs_core.testing import vertex_normals
    N = vertex_normals(W, F)
    base = stripe_components(W, F, N)
    assert base == stripe_components(W, F)
    assert stripe_components(W, F, 0.6 * N) == base == stripe_components(W, F, 3.0 * N)


def test_several_piece_sizes_in_one_pass_equal_one_at_a_time():
    V, F = icosphere(4)
    W = bumped(V, 0.1)
    floors = (1e-3, 1e-4, 0.0)
    both = stripe_components(W, F, min_area=floors)
    assert isinstance(both, np.ndarray) and both.shape == (3,)
    assert both.tolist() == [stripe_components(W, F, min_area=m) for m in floors]
    assert both[0] <= both[1] <= both[2]                       # a lower floor counts more
    assert stripe_components(V, np.zeros((0, 3), dtype=int), min_area=floors).tolist() == [0, 0, 0]


@pytest.mark.parametrize("kw, name", [({"stripes": 0.0}, "stripes"), ({"stripes": np.nan}, "stripes"),
                                      ({"directions": 0}, "directions"),
                                      ({"directions": 2.5}, "directions"),
                                      ({"directions": np.nan}, "directions"),
                                      ({"directions": np.inf}, "directions"),
                                      ({"min_area": 1.0}, "min_area"),
                                      ({"min_area": -0.1}, "min_area"),
                                      ({"min_area": [[1e-3]]}, "min_area"),
                                      ({"min_area": []}, "min_area"),
                                      ({"normals": np.zeros((3, 3))}, "normals")])
def test_bad_arguments_are_named(kw, name):
    V, F = icosphere(1)
    with pytest.raises(InvalidParameterError, match=name):
        stripe_components(V, F, **kw)
