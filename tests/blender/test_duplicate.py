"""Duplicating a GERBS object: the copy gets its own surface on its first evaluation.

A copy (``obj.copy()``, Shift+D, Alt+D) carries the modifier with the original's hidden
result in its Result input; that result is fresh for the copy too (same mesh), so the
first evaluation shows it, and the copy's sync must build its own result from it.
"""
import bpy
import numpy as np
import pytest

from .helpers import evaluated, export_and_reimport, make_object

pytestmark = pytest.mark.blender

R = 2


def _duplicate(obj, how):
    """A copy of `obj` made the way `how` names, in the scene, active."""
    if how in ("copy", "copy_linked_mesh"):
        dup = obj.copy()
        if how == "copy":
            dup.data = obj.data.copy()
        bpy.context.scene.collection.objects.link(dup)
        return dup
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.duplicate(linked=how == "alt_d")  # Shift+D, Alt+D
    return bpy.context.active_object


def _errors(*objects):
    from blender_addon import api
    return [api.status(o)["error"] for o in objects]


HOWS = ["copy", "copy_linked_mesh", "shift_d", "alt_d"]


@pytest.mark.parametrize("how", HOWS)
def test_a_copy_shows_its_own_surface_at_once_and_exports_it(blender, how, tmp_path):
    from blender_addon import api
    from blender_addon import geometry_nodes as gn

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=R)
    P = evaluated(obj)
    dup = _duplicate(obj, how)
    assert dup is not obj and (dup.data is obj.data) == (how in ("copy_linked_mesh", "alt_d"))
    Q = evaluated(dup)  # one depsgraph evaluation
    assert len(Q) == len(P) > len(obj.data.vertices)  # the surface, not the 42-vertex cage
    assert np.array_equal(Q, P)  # the same mesh: the same surface
    assert _errors(obj, dup) == ["", ""]
    assert np.array_equal(evaluated(obj), P)
    assert gn.get_result(dup.modifiers[0]) != gn.get_result(obj.modifiers[0])
    got = export_and_reimport(dup, tmp_path / "copy.obj")  # (apply_modifiers)
    assert len(got.data.vertices) == len(P)


@pytest.mark.parametrize("how", HOWS)
def test_a_copy_stays_valid_when_the_original_is_edited_or_deleted(blender, how):
    from blender_addon import api, ids

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=R)
    P = evaluated(obj)
    dup = _duplicate(obj, how)
    assert np.array_equal(evaluated(dup), P)
    shared = dup.data is obj.data
    obj.data.vertices[0].co.z += 0.3
    obj.data.update()
    P2 = evaluated(obj)
    assert np.abs(P2 - P).max() > 0.01
    # a linked duplicate shares the mesh: the same edit; else the copy is as it was
    assert np.array_equal(evaluated(dup), P2 if shared else P)
    assert _errors(obj, dup) == ["", ""]
    before = {o.name for o in bpy.data.objects if o.get(ids.RESULT_TAG)}
    bpy.data.objects.remove(obj)
    Q = evaluated(dup)
    assert np.array_equal(Q, P2 if shared else P)
    assert _errors(dup) == [""]
    after = {o.name for o in bpy.data.objects if o.get(ids.RESULT_TAG)}
    assert after < before  # the original's result went with it, the copy's stays


def test_copies_render_their_own_render_resolution(blender):
    """Render Resolution above Resolution: the copy's render result is its own too."""
    from blender_addon import api
    from blender_addon import geometry_nodes as gn

    from .test_stack import _render_counts

    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.active_object
    api.add_surface(cube, resolution=2, render_resolution=4)
    dup = _duplicate(cube, "shift_d")
    assert len(evaluated(dup)) == len(evaluated(cube)) == 26
    counts = _render_counts()
    assert counts[cube.name] == counts[dup.name] == 8 + 12 * 3 + 6 * 9
    assert gn.get_result(dup.modifiers[0], True) != gn.get_result(cube.modifiers[0], True)
    assert _errors(cube, dup) == ["", ""]


@pytest.mark.parametrize("below", [None, "TRIANGULATE"])
def test_a_linked_duplicate_follows_edits_made_in_the_other_objects_edit_mode(blender, below):
    """Found by a test of linked duplicates: with the shared mesh in Edit Mode on one
    object, the other (in Object Mode) read the mesh's arrays, which keep the state before
    Edit Mode, found nothing changed and showed its cage (no error), or with a modifier
    below GERBS failed reading its attributes ("internal error", a raw TypeError from
    api.update). Blender evaluates every user of an edit mesh from it; so does the sync."""
    import bmesh
    from blender_addon import api

    from .helpers import fresh_surface, positions, topology

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=R)
    dup = _duplicate(obj, "alt_d")
    if below:
        dup.modifiers.new("below", below)
    n_before = len(evaluated(dup))
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    assert dup.mode == "OBJECT" and dup.data.is_editmode
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    bm.verts[0].co.z += 0.4
    bmesh.update_edit_mesh(obj.data)
    bpy.context.view_layer.update()
    P_dup, P_obj = evaluated(dup), evaluated(obj)
    api.update(dup)  # no exception, no error
    assert _errors(obj, dup) == ["", ""]
    bpy.ops.object.mode_set(mode="OBJECT")
    X = positions(obj.data)
    want = fresh_surface(X, *topology(obj.data), R)
    assert np.abs(P_obj - want).max() <= 1e-5
    if below is None:
        assert np.abs(P_dup - want).max() <= 1e-5  # the edited surface, not the cage
    else:
        assert len(P_dup) == n_before > len(X)  # the surface triangulated, not the cage
        assert np.abs(evaluated(dup)[:len(X)] - X).max() <= 1e-5
