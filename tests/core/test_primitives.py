"""Test meshes (gerbs_core.datasets.primitives) and the OBJ reader/writer (gerbs_core.datasets.obj)."""
import numpy as np
import pytest

from gerbs_core.datasets import primitives
from gerbs_core.errors import InvalidMeshError, InvalidParameterError
from gerbs_core.mesh import MeshTopology, validate_geometry
from gerbs_core.datasets.obj import parse_obj, read_obj, write_obj


def _face_normals(v, topo):
    """Vector area of each face (Newell), relative to its first corner."""
    out = np.zeros((topo.n_faces, 3))
    for f in range(topo.n_faces):
        p = v[topo.face(f)] - v[topo.face(f)[0]]
        out[f] = 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(0)
    return out


def _signed_volume(v, topo):
    vol = 0.0
    for f in range(topo.n_faces):
        c = topo.face(f)
        for k in range(1, len(c) - 1):
            vol += np.dot(v[c[0]], np.cross(v[c[k]], v[c[k + 1]])) / 6.0
    return vol


@pytest.mark.parametrize("s", [0, 1, 2])
def test_icosphere_counts_closed_outward(s):
    v, f = primitives.icosphere(s)
    assert v.dtype == np.float64 and v.shape == (10 * 4**s + 2, 3)
    assert f.shape == (20 * 4**s, 3)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-15)
    T = MeshTopology(f, len(v))
    validate_geometry(v, T)
    assert T.is_closed and T.euler_characteristic == 2
    n = _face_normals(v, T)
    centroid = v[f].mean(1)
    assert np.all(np.einsum("ij,ij->i", n, centroid) > 0)  # every face outward
    # volume approaches the ball's from below
    vol = _signed_volume(v, T)
    assert 0 < vol < 4 * np.pi / 3


def test_uv_sphere_poles_are_triangle_fans():
    seg, rings = 7, 5
    v, f = primitives.uv_sphere(seg, rings)
    assert len(v) == seg * (rings - 1) + 2 and len(f) == seg * rings
    T = MeshTopology(f, len(v))
    validate_geometry(v, T)
    assert T.is_closed and T.euler_characteristic == 2
    for pole in (0, len(v) - 1):
        assert abs(abs(v[pole, 2]) - 1) < 1e-15
        assert T.vertex_valence[pole] == seg
        assert set(T.face_sizes[T.star_faces[T.star_offsets[pole]:T.star_offsets[pole + 1]]]) == {3}
    assert sorted(set(T.face_sizes.tolist())) == [3, 4]
    assert int((T.face_sizes == 3).sum()) == 2 * seg
    n = _face_normals(v, T)
    centroid = np.array([v[list(x)].mean(0) for x in f])
    assert np.all(np.einsum("ij,ij->i", n, centroid) > 0)
    assert _signed_volume(v, T) > 0


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_grid_layout_and_boundary(kind):
    n, m, size = 4, 3, 2.0
    v, f = primitives.grid(n, m, kind=kind, size=size)
    assert v.shape == ((n + 1) * (m + 1), 3) and np.all(v[:, 2] == 0)
    assert f.shape == ((n * m, 4) if kind == "quad" else (2 * n * m, 3))
    np.testing.assert_allclose(v[2 * (n + 1) + 3], [3 * size / n, 2 * size / n, 0])
    np.testing.assert_allclose(v.max(0), [size, size * m / n, 0])
    T = MeshTopology(f, len(v))
    assert T.euler_characteristic == 1
    (loop,) = T.boundary_loops
    assert len(loop) == 2 * (n + m)
    assert np.all(_face_normals(v, T)[:, 2] > 0)  # counter-clockwise seen from +z
    inner = ~T.vertex_is_boundary
    assert set(T.vertex_valence[inner].tolist()) == ({4} if kind == "quad" else {6})


def test_mixed_mesh_has_the_advertised_mixture():
    for bend in (0.0, 0.4):
        v, f = primitives.mixed_mesh(bend=bend)
        T = MeshTopology(f, len(v))
        validate_geometry(v, T)
        assert sorted(set(T.face_sizes.tolist())) == [3, 4, 5, 6]
        assert T.n_vertices == 35 and T.n_faces == 31 and T.n_edges == 65
        inner = ~T.vertex_is_boundary
        assert set(T.vertex_valence[inner].tolist()) == {3, 4, 5, 6, 7, 8}
        assert len(T.boundary_loops) == 1 and T.euler_characteristic == 1
        assert np.all(_face_normals(v, T)[:, 2] > 0)
    # every face strictly convex in the xy projection (counter-clockwise turns)
    for face in f:
        p = v[list(face), :2]
        d = np.roll(p, -1, 0) - p
        turn = d[:, 0] * np.roll(d, -1, 0)[:, 1] - d[:, 1] * np.roll(d, -1, 0)[:, 0]
        assert np.all(turn > 1e-3)
    # bend makes the hexagon non-planar
    hexa = [face for face in f if len(face) == 6][0]
    p = v[list(hexa)]
    assert np.linalg.svd(p - p.mean(0), compute_uv=False)[-1] > 1e-3
    assert np.all(primitives.mixed_mesh()[0][:, 2] == 0)


def test_delaunay_patch_is_a_delaunay_triangulation_of_the_square():
    v, f = primitives.delaunay_patch(120, seed=3)
    assert v.shape == (120, 3) and np.all(v[:, 2] == 0)
    np.testing.assert_array_equal(v[:4, :2], [[0, 0], [1, 0], [1, 1], [0, 1]])
    assert np.all((v[:, :2] >= 0) & (v[:, :2] <= 1))
    T = MeshTopology(f, len(v))
    validate_geometry(v, T)
    assert np.all(_face_normals(v, T)[:, 2] > 0)
    (loop,) = T.boundary_loops
    assert set(loop.tolist()) == {0, 1, 2, 3}  # the boundary is the square
    # empty circumcircles
    p = v[:, :2]
    a, b, c = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
    d = 2 * (a[:, 0] * (b[:, 1] - c[:, 1]) + b[:, 0] * (c[:, 1] - a[:, 1]) + c[:, 0] * (a[:, 1] - b[:, 1]))
    sq = lambda q: (q ** 2).sum(1)  # noqa: E731
    ux = (sq(a) * (b[:, 1] - c[:, 1]) + sq(b) * (c[:, 1] - a[:, 1]) + sq(c) * (a[:, 1] - b[:, 1])) / d
    uy = (sq(a) * (c[:, 0] - b[:, 0]) + sq(b) * (a[:, 0] - c[:, 0]) + sq(c) * (b[:, 0] - a[:, 0])) / d
    centre = np.stack([ux, uy], 1)
    r2 = sq(a - centre)
    dist2 = ((p[None] - centre[:, None]) ** 2).sum(-1)
    dist2[np.arange(len(f))[:, None], f] = np.inf
    assert np.all(dist2 > r2[:, None] * (1 - 1e-9))
    # reproducible, seed-dependent, and accepts given points
    np.testing.assert_array_equal(primitives.delaunay_patch(120, seed=3)[0], v)
    assert not np.array_equal(primitives.delaunay_patch(120, seed=4)[0], v)
    v2, f2 = primitives.delaunay_patch(points=v[:, :2])
    assert np.array_equal(v2, v) and len(f2) == len(f)


def test_suzanne_reads_the_example():
    v, f = primitives.suzanne()
    assert v.shape == (507, 3) and len(f) == 500
    sizes = np.array([len(x) for x in f])
    assert (sizes == 4).sum() == 468 and (sizes == 3).sum() == 32
    T = MeshTopology(f, len(v))
    validate_geometry(v, T)
    assert not T.is_closed and len(T.boundary_loops) == 4


@pytest.mark.parametrize("call, name", [
    (lambda: primitives.icosphere(-1), "subdivisions"),
    (lambda: primitives.icosphere(1.5), "subdivisions"),
    (lambda: primitives.uv_sphere(2, 4), "segments"),
    (lambda: primitives.uv_sphere(5, 1), "rings"),
    (lambda: primitives.grid(0, 2), "n"),
    (lambda: primitives.grid(2, 2, kind="hex"), "kind"),
    (lambda: primitives.delaunay_patch(3), "n_points"),
])
def test_bad_parameters_are_named(call, name):
    with pytest.raises(InvalidParameterError) as info:
        call()
    assert info.value.name == name


def test_obj_round_trip_is_exact(tmp_path):
    v, f = primitives.mixed_mesh(bend=0.3)
    v = v + np.random.default_rng(0).normal(scale=1e-3, size=v.shape)
    path = tmp_path / "m.obj"
    write_obj(path, v, f, name="mixed")
    v2, f2 = read_obj(path)
    assert np.array_equal(v2, v) and f2 == [tuple(x) for x in f]
    vi, fi = primitives.icosphere(1)
    write_obj(path, vi, fi)
    v3, f3 = read_obj(path)
    assert np.array_equal(v3, vi) and np.array_equal(np.array(f3), fi)


def test_obj_parser_forms_and_errors():
    text = """# comment
o thing
v 0 0 0
v 1 0 0
vt 0.5 0.5
v 1 1 0
vn 0 0 1
v 0 1 0 1.0
v 0.5 1.5 0
s off
f 1/1/1 2/1/1 3/1/1
f 1//1 3//1 -2//1
f -4/1 -3/1 -1/1 4/1
"""
    v, f = parse_obj(text)
    assert v.shape == (5, 3)
    assert f == [(0, 1, 2), (0, 2, 3), (1, 2, 4, 3)]
    with pytest.raises(InvalidMeshError) as info:
        parse_obj("v 0 0 0\nv 1 0\n")
    assert info.value.problem == "bad_shape" and info.value.indices == (2,)
    with pytest.raises(InvalidMeshError) as info:
        parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n")
    assert info.value.indices == (4,) and "line 4" in str(info.value)
