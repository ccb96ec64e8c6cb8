"""Mesh input at its edges: OBJ lines that are not numbers, primitives' parameter checks,
face lists whose entries overflow or are all negative, a stray vertex, a one-sided
(Moebius) strip, a topology of the wrong size, the fairness rule's constants. Each bad
input raises the specific error naming what is wrong; what can be repaired is repaired
and reported.
"""
import numpy as np
import pytest

from gerbs_core.datasets import primitives as P
from gerbs_core.datasets.obj import parse_obj, write_obj
from gerbs_core.errors import InvalidMeshError, InvalidParameterError
from gerbs_core.mesh.agreement import FairnessRule
from gerbs_core.mesh.repair import repair_mesh
from gerbs_core.mesh.surface import BlendingSurface
from gerbs_core.mesh.topology import MeshTopology
from gerbs_core.mesh.validation import validate_geometry


def test_obj_vertex_with_a_word_names_its_line():
    with pytest.raises(InvalidMeshError, match="OBJ line 2: malformed vertex") as exc:
        parse_obj("v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n")
    assert exc.value.problem == "bad_shape" and exc.value.indices == (2,)


def test_write_obj_refuses_points_that_are_not_3d(tmp_path):
    with pytest.raises(InvalidMeshError, match=r"vertices must have shape \(V, 3\)"):
        write_obj(tmp_path / "m.obj", np.zeros((3, 2)), [(0, 1, 2)])
    assert not (tmp_path / "m.obj").exists()


@pytest.mark.parametrize("call, name", [
    (lambda: P.delaunay_patch(points=np.zeros((2, 2))), "points"),
    (lambda: P.delaunay_patch(points=np.zeros((5, 3))), "points"),
    (lambda: P.quad_patch(3, jitter=0.5), "jitter"),
    (lambda: P.quad_patch(3, jitter=-0.1), "jitter"),
])
def test_primitive_parameters_are_checked(call, name):
    with pytest.raises(InvalidParameterError) as exc:
        call()
    assert exc.value.name == name


def test_face_entries_too_large_for_an_index_are_bad_shape():
    with pytest.raises(InvalidMeshError) as exc:
        MeshTopology([[0, 1, 2], [0, 2, 2 ** 70]])
    assert exc.value.problem == "bad_shape" and exc.value.indices == (1,)


def test_a_nested_face_entry_is_bad_shape():
    with pytest.raises(InvalidMeshError) as exc:
        MeshTopology([[0, 1, 2], [0, [2, 3], 1]])
    assert exc.value.problem == "bad_shape" and exc.value.indices == (1,)


def test_all_negative_indices_are_out_of_range():
    with pytest.raises(InvalidMeshError) as exc:
        MeshTopology([[-1, -2, -3]])
    assert exc.value.problem == "index_out_of_range"


def test_k_ring_beyond_the_mesh_is_the_whole_mesh_and_repr_counts():
    V, F = P.cube()
    T = MeshTopology(F, len(V))
    assert sorted(T.k_ring(0, 50, include_self=True).tolist()) == list(range(8))
    assert sorted(T.k_ring(0, 50).tolist()) == list(range(1, 8))
    assert repr(T) == "MeshTopology(V=8, E=12, F=6, boundary_edges=0)"
    G, GF = P.grid(2)
    assert repr(MeshTopology(GF, len(G))).endswith("boundary_edges=8)")


def test_a_stray_coordinate_is_an_outlier_vertex():
    V, F = P.grid(3)
    V = V.copy()
    V[4] = [0.5, 0.5, 1e9]              # an interior vertex thrown far away
    with pytest.raises(InvalidMeshError, match="outlier_vertex") as exc:
        validate_geometry(V, MeshTopology(F, len(V)))
    assert exc.value.problem == "outlier_vertex" and 4 in exc.value.indices


@pytest.mark.parametrize("far", [1e8, 1e14, 1e20, 3.4e38])
def test_a_stray_coordinate_is_refused_before_its_faces_pass_for_zero_area(far):
    """A newcomer's walk (2026-12-07): from 1e14 on, the faces of a Cube vertex thrown far
    away have no area to the rounding, the zero-area repair dropped them and the surface of
    the rest was built with warnings only (Blender stores ``co.x = inf`` as 3.4e38)."""
    from gerbs_core.mesh import BlendingSurface
    V, F = P.cube()
    V = V.copy()
    V[7, 0] = far
    with pytest.raises(InvalidMeshError, match="outlier_vertex") as exc:
        BlendingSurface(V, F)
    assert exc.value.problem == "outlier_vertex" and list(exc.value.indices) == [7]
    # a loose vertex that far is in no face: ignored, as every loose vertex
    L = np.concatenate([P.cube()[0], [[far, 0.0, 0.0]]])
    assert [w.tag for w in BlendingSurface(L, F).warnings] == ["unused_vertex"]


def test_collapsed_slivers_do_not_make_the_real_vertices_outliers():
    """A review (2026-12-07): 60 collapsed triangles (three vertices within 2e-9 of a point)
    beside a 6 x 6 grid made the median edge 2e-9 once the outlier check ran before the
    zero-area repair, and every real vertex an outlier; the median is now of the faces
    with an area, and the mesh builds as before, its slivers dropped."""
    from gerbs_core.mesh import BlendingSurface
    V, F = P.grid(6)
    F = [tuple(f) for f in np.asarray(F).tolist()]
    rng = np.random.default_rng(0)
    extra = []
    for k in range(60):
        c = V[rng.integers(len(V))]
        d = rng.standard_normal(3)
        d /= np.linalg.norm(d)
        extra += [c, c + 1e-9 * d, c + 2e-9 * d]
        F.append((len(V) + 3 * k, len(V) + 3 * k + 1, len(V) + 3 * k + 2))
    s = BlendingSurface(np.concatenate([V, extra]), F)
    assert {"degenerate_face", "unused_vertex"} <= {w.tag for w in s.warnings}


def _moebius(n=12):
    """A Moebius strip of n quads (one-sided: no consistent orientation)."""
    t = 2 * np.pi * np.arange(n) / n
    X = []
    for s in (-0.3, 0.3):
        X.append(np.stack([(1 + s * np.cos(t / 2)) * np.cos(t),
                           (1 + s * np.cos(t / 2)) * np.sin(t), s * np.sin(t / 2)], -1))
    X = np.concatenate(X)                 # 0..n-1 one edge, n..2n-1 the other
    F = [(i, i + 1, n + i + 1, n + i) for i in range(n - 1)] + [(n - 1, n, 0, 2 * n - 1)]   # a(2 pi) = b(0), b(2 pi) = a(0)
    return X, F


def test_moebius_strip_is_cut_open_and_reported():
    X, F = _moebius()
    with pytest.raises(InvalidMeshError):
        MeshTopology(F, len(X))                      # not orientable as given
    rep = repair_mesh(X, F)
    tags = [w.tag for w in rep.warnings]
    assert "non_orientable" in tags
    w = rep.warnings[tags.index("non_orientable")]
    assert str(w) == w.message and w.edges        # the cut seam's edges are named
    assert rep.topology.n_faces == len(F)
    s = BlendingSurface(X, F)
    assert "non_orientable" in [w.tag for w in s.warnings]
    # still interpolates every vertex, from every face around it
    T = s.topology
    S = s.evaluate(T.corner_face, s.layouts.corners)
    assert np.abs(S - s.vertices[T.face_vertices]).max() <= 1e-12


def test_topology_of_another_size_is_refused():
    V, F = P.cube()
    with pytest.raises(InvalidParameterError) as exc:
        BlendingSurface(V[:-1], MeshTopology(F, len(V)))
    assert exc.value.name == "vertices"


@pytest.mark.parametrize("kw, name", [
    (dict(mu=-1.0), "mu"), (dict(lam=float("nan")), "lam"),
    (dict(sharp_from=80.0, sharp_to=50.0), "sharp_from"),
    (dict(damping=0.0), "damping"), (dict(damping=1.5), "damping"),
    (dict(sweeps=1.5), "sweeps"), (dict(choice_rounds=-1), "choice_rounds"),
    (dict(resolution=1), "resolution"), (dict(resolution=2.5), "resolution"),
])
def test_fairness_rule_constants_are_checked(kw, name):
    with pytest.raises(InvalidParameterError) as exc:
        FairnessRule(**kw)
    assert exc.value.name == name


def _ngon_lattice():
    from gerbs_core.mesh.lattice import Lattice
    V, F = P.ngon_ring(6)               # triangles, quads and one hexagon
    T = MeshTopology(F, len(V))
    X = V[T.face_vertices]
    mean = np.add.reduceat(X, T.face_offsets[:-1], axis=0) / T.face_sizes[:, None]
    return T, Lattice(T, 4), X, mean


def test_lattice_fan_centres_are_used_and_checked():
    T, lat, X, mean = _ngon_lattice()
    base = lat.map_to_polygon(X)
    np.testing.assert_array_equal(lat.map_to_polygon(X, centers=mean), base)
    lifted = lat.map_to_polygon(X, centers=mean + [0.0, 0.0, 0.1])
    ngon = T.face_sizes[lat.face] >= 5
    assert ngon.any()
    np.testing.assert_array_equal(lifted[~ngon], base[~ngon])   # only the n-gons' fans move
    assert np.abs(lifted[ngon] - base[ngon]).max() == pytest.approx(0.1)
    with pytest.raises(InvalidParameterError) as exc:
        lat.map_to_polygon(X, centers=mean[:-1])
    assert exc.value.name == "centers"


def test_lattice_centres_are_checked_without_ngons_too():
    from gerbs_core.mesh.lattice import Lattice
    V, F = P.grid(2)
    T = MeshTopology(F, len(V))
    with pytest.raises(InvalidParameterError):
        Lattice(T, 3).map_to_polygon(V[T.face_vertices], centers=np.zeros((3, 2)))
