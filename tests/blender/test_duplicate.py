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
