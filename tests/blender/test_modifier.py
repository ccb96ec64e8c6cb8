"""The modifier on real meshes: counts, interpolation, settings, visibility, apply, remove."""
import bpy
import numpy as np
import pytest

from .helpers import (evaluated, evaluated_faces, evaluated_triangles, make_object, positions,
                      topology)

pytestmark = pytest.mark.blender

R = 3


@pytest.mark.parametrize("kind", ["suzanne", "icosphere", "uv_sphere", "grid", "mixed"])
def test_surface_counts_and_interpolation(blender, kind):
    from blender_addon import api

    obj = make_object(kind)
    X = positions(obj.data)
    offsets, corners = topology(obj.data)
    api.add_surface(obj, resolution=R)
    P = evaluated(obj)
    # expected count from the mesh alone: vertices, edge interiors, face interiors
    V, E = len(obj.data.vertices), len(obj.data.edges)
    sizes = np.diff(offsets)
    tri = (R - 1) * (R - 2) // 2
    interior = np.where(sizes == 3, tri, np.where(sizes == 4, (R - 1) ** 2,
                                                  1 + sizes * (R - 1) + sizes * tri))
    assert len(P) == V + E * (R - 1) + interior.sum()
    # every base vertex is an output point (first V samples), to float32 precision
    assert np.abs(P[:V] - X).max() <= 1e-6
    # output faces, like Subdivision Surface: r x r quads in every quad, r^2 triangles in
    # every triangle, n r^2 triangles in an n-gon's fan; all indices valid
    out_offsets, out_corners = evaluated_faces(obj)
    out_sizes = np.diff(out_offsets)
    want = np.where(sizes == 4, R * R, np.where(sizes == 3, R * R, sizes * R * R))
    assert len(out_sizes) == want.sum() and out_corners.max() < len(P)
    assert np.array_equal(np.sort(out_sizes), np.sort(np.repeat(np.where(sizes == 4, 4, 3), want)))
    assert len(evaluated_triangles(obj)) == np.where(sizes == 4, 2 * R * R, want).sum()
    # the base mesh itself is untouched
    assert np.array_equal(positions(obj.data), X)
    o2, c2 = topology(obj.data)
    assert np.array_equal(o2, offsets) and np.array_equal(c2, corners)


def test_settings_are_modifier_inputs_and_change_the_surface(blender):
    from blender_addon import api, engine

    obj = make_object("icosphere")
    mod = api.add_surface(obj, resolution=2, kernel="logistic")
    assert api.get_settings(obj)["kernel"] == "logistic"
    P2 = evaluated(obj)
    api.set_settings(obj, resolution=4)
    P4 = evaluated(obj)  # the handler rebuilds inside the depsgraph update
    assert len(P4) > len(P2)
    st = engine.get_state(obj, mod)
    api.set_settings(obj, kernel="bfbs", bfbs_left=1, bfbs_right=1)
    P4b = evaluated(obj)
    assert len(P4b) == len(P4) and np.abs(P4b - P4).max() > 1e-4
    assert engine.get_state(obj, mod) is not st  # settings change -> rebuild
    with pytest.raises(ValueError, match="kernel"):
        api.set_settings(obj, kernel="nope")


@pytest.mark.parametrize("kernel", ["erbs", "bfbs", "logistic", "affine"])
def test_every_kernel_builds_an_interpolating_surface(blender, kernel):
    from blender_addon import api

    obj = make_object("icosphere")
    # r=4: at r=2 every sample is an edge midpoint, where symmetric kernels all give 1/2
    api.add_surface(obj, resolution=4, kernel="logistic")
    reference = evaluated(obj)
    api.set_settings(obj, kernel=kernel, alpha=2.0, bfbs_left=3)
    P = evaluated(obj)
    X = positions(obj.data)
    assert np.all(np.isfinite(P)) and np.abs(P[: len(X)] - X).max() <= 1e-6
    # the kernel changes the blend between vertices (logistic is the reference)
    assert (np.abs(P - reference).max() > 1e-4) == (kernel != "logistic")


def test_materials_follow_the_faces(blender):
    from blender_addon import api

    obj = make_object("grid")
    for name in ("red", "blue"):
        obj.data.materials.append(bpy.data.materials.new(name))
    index = np.zeros(len(obj.data.polygons), dtype=np.int32)
    index[::3] = 1
    obj.data.polygons.foreach_set("material_index", index)
    obj.data.update()
    api.add_surface(obj, resolution=2)  # quads: 4 quads per face, faces in order
    dg = bpy.context.evaluated_depsgraph_get()
    mesh = obj.evaluated_get(dg).data
    got = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("material_index", got)
    assert [m.name for m in mesh.materials] == ["red", "blue"]
    assert np.bincount(got).tolist() == [4 * int((index == 0).sum()), 4 * int((index == 1).sum())]


def test_visibility_toggle_shows_base_or_surface(blender):
    from blender_addon import api

    obj = make_object("grid")
    mod = api.add_surface(obj, resolution=R)
    X = positions(obj.data)
    assert len(evaluated(obj)) > len(X)
    mod.show_viewport = False
    base = evaluated(obj)
    assert base.shape == X.shape and np.abs(base - X).max() == 0.0
    mod.show_viewport = True
    assert len(evaluated(obj)) > len(X)


def test_several_objects_each_with_own_surface(blender):
    from blender_addon import api

    a, b = make_object("icosphere"), make_object("grid")
    ma, mb = api.add_surface(a, resolution=2), api.add_surface(b, resolution=3)
    from blender_addon import geometry_nodes as gn
    ra, rb = gn.get_result(ma), gn.get_result(mb)
    assert ra is not None and rb is not None and ra != rb
    Pa, Pb = evaluated(a), evaluated(b)
    b.data.vertices[0].co.z += 0.3
    b.data.update()
    assert np.array_equal(evaluated(a), Pa)
    assert np.abs(evaluated(b) - Pb).max() > 0.01


def test_duplicated_object_gets_its_own_result(blender):
    from blender_addon import api
    from blender_addon import geometry_nodes as gn

    a = make_object("icosphere")
    api.add_surface(a, resolution=2)
    b = a.copy()
    b.data = a.data.copy()
    bpy.context.scene.collection.objects.link(b)
    b.data.vertices[0].co.z += 0.3
    b.data.update()
    Pa_before = evaluated(a)
    Pb = evaluated(b)
    assert gn.get_result(a.modifiers[0]) != gn.get_result(b.modifiers[0])
    assert np.abs(Pb - Pa_before).max() > 0.01
    assert np.array_equal(evaluated(a), Pa_before)


def test_apply_bakes_real_mesh_data(blender):
    from blender_addon import api

    obj = make_object("suzanne")
    api.add_surface(obj, resolution=2)
    P = evaluated(obj)
    n_objects = len(bpy.data.objects)
    api.apply(obj)
    assert len(obj.modifiers) == 0
    assert np.abs(positions(obj.data) - P).max() == 0.0
    assert len(bpy.data.objects) == n_objects - 1  # hidden result object cleaned up


def test_apply_through_blender_operator(blender):
    from blender_addon import api

    obj = make_object("grid")
    mod = api.add_surface(obj, resolution=2)
    P = evaluated(obj)
    bpy.ops.object.modifier_apply(modifier=mod.name)
    assert np.abs(positions(obj.data) - P).max() == 0.0
    evaluated(obj)  # the depsgraph handler garbage-collects the orphaned result
    assert not [o for o in bpy.data.objects if o.get("gerbs_result")]


def test_remove_restores_base_and_cleans_up(blender):
    from blender_addon import api

    obj = make_object("mixed")
    X = positions(obj.data)
    offsets, corners = topology(obj.data)
    api.add_surface(obj, resolution=R)
    assert [o for o in bpy.data.objects if o.get("gerbs_result")]
    assert bpy.ops.object.gerbs_remove() == {"FINISHED"}
    P = evaluated(obj)
    assert P.shape == X.shape and np.abs(P - X).max() == 0.0
    o2, c2 = topology(obj.data)
    assert np.array_equal(o2, offsets) and np.array_equal(c2, corners)
    assert not [o for o in bpy.data.objects if o.get("gerbs_result")]
    assert not [m for m in bpy.data.meshes if m.name.startswith("GERBS Result")]


def test_remove_through_blender_operator_cleans_up(blender):
    from blender_addon import api

    obj = make_object("grid")
    mod = api.add_surface(obj, resolution=2)
    bpy.ops.object.modifier_remove(modifier=mod.name)
    evaluated(obj)
    assert not [o for o in bpy.data.objects if o.get("gerbs_result")]


@pytest.mark.parametrize("kind", ["suzanne", "grid", "mixed", "icosphere"])
@pytest.mark.parametrize("r", [1, 3])
def test_result_mesh_edges_are_valid(blender, kind, r):
    """The result mesh's edges are written from the lattice (not by Blender's edge
    hashing): Blender's validate() finds nothing to fix and calc_edges adds nothing."""
    from blender_addon import api
    from blender_addon import geometry_nodes as gn

    obj = make_object(kind)
    api.add_surface(obj, resolution=r)
    mesh = gn.get_result(obj.modifiers[-1]).data
    n = len(mesh.edges)
    assert n > 0
    copy = mesh.copy()
    try:
        assert not copy.validate(verbose=False)  # no repeated or invalid edge
        copy.update(calc_edges=True)  # Blender's own edge hashing finds no missing edge
        assert len(copy.edges) == n
    finally:
        bpy.data.meshes.remove(copy)
