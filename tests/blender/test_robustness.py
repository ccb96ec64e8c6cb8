"""Robustness in real bpy (issue 7 item 3): errors in the panel and the status bar,
removing / reloading the add-on while objects use the modifier, and undo/redo
across add, apply and remove done through the operators (as a user would)."""
import importlib

import bpy
import numpy as np
import pytest

from .helpers import evaluated, link_object, make_object, positions, topology

pytestmark = pytest.mark.blender

NAN = ([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, -1, 0), (float("nan"), 0, 1)],
       [(0, 1, 2), (1, 0, 3), (0, 1, 4)])  # no surface through a NaN vertex


def _snapshot(obj):
    offsets, corners = topology(obj.data)
    return positions(obj.data), offsets, corners


def _same_base(obj, snap):
    X, offsets, corners = _snapshot(obj)
    return (np.array_equal(X, snap[0]) and np.array_equal(offsets, snap[1])
            and np.array_equal(corners, snap[2]))


def _warnings(obj):
    return [(w.type, w.message) for w in obj.modifiers[0].node_warnings]


def test_invalid_mesh_error_shows_in_panel_and_status_bar(blender):
    from blender_addon import api, handlers
    from blender_addon.api import GERBSSyncError

    obj = link_object("bad", *NAN)
    snap = _snapshot(obj)
    with pytest.raises(GERBSSyncError, match="non_finite"):
        api.add_surface(obj, resolution=2)
    P = evaluated(obj)  # the depsgraph handler runs: status bar updated
    assert np.array_equal(P, snap[0], equal_nan=True)
    ((kind, message),) = _warnings(obj)  # the modifier panel's error line
    assert kind == "ERROR" and "non_finite" in message
    assert "non_finite" in api.status(obj)["error"]  # the GERBS status panel
    assert handlers.status_message is not None and "non_finite" in handlers.status_message
    assert obj.name in handlers.status_message
    import blender_addon
    blender_addon.unregister()  # the add-on's message leaves the status bar with it
    assert handlers.status_message is None
    blender_addon.register()
    evaluated(obj)  # still invalid: shown again
    assert "non_finite" in handlers.status_message


def _add_fin(mesh):
    """Add a triangle on an interior edge: that edge now has three faces."""
    import bmesh

    bm = bmesh.new()
    bm.from_mesh(mesh)
    edge = next(e for e in bm.edges if len(e.link_faces) == 2)
    v = bm.verts.new((edge.verts[0].co + edge.verts[1].co) / 2 + edge.verts[0].normal * 0.5)
    bm.faces.new((edge.verts[0], edge.verts[1], v))
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()


def test_live_edit_that_breaks_the_mesh_then_fixes_it(blender):
    """A live edit adding a fin (a non-manifold edge): repaired, a warning line in the
    panel; then one moving a vertex to NaN: error in the panel and the status bar, the
    (edited) base mesh shown as is; undoing the edits restores the surface."""
    from blender_addon import api, handlers

    obj = make_object("grid")
    name = obj.name
    api.add_surface(obj, resolution=2)
    good = evaluated(obj)
    assert handlers.status_message is None
    bpy.ops.ed.undo_push(message="surface")
    _add_fin(obj.data)
    bpy.ops.ed.undo_push(message="fin")
    P = evaluated(obj)
    assert len(P) > len(good) and handlers.status_message is None  # built with the fin
    ((kind, message),) = _warnings(obj)
    assert kind == "WARNING" and "non_manifold_edge" in message
    _undo()
    obj = bpy.data.objects[name]
    assert np.abs(evaluated(obj) - good).max() <= 1e-6
    obj.data.vertices[0].co = (float("nan"), 0.0, 0.0)
    obj.data.update()
    bpy.ops.ed.undo_push(message="nan")
    P = evaluated(obj)
    assert np.array_equal(P, positions(obj.data), equal_nan=True)  # passed through
    ((kind, message),) = _warnings(obj)
    assert kind == "ERROR" and "non_finite" in message
    assert "non_finite" in handlers.status_message and name in handlers.status_message
    _undo()
    obj = bpy.data.objects[name]
    assert np.abs(evaluated(obj) - good).max() <= 1e-6
    assert _warnings(obj) == [] and api.status(obj)["error"] == ""
    assert handlers.status_message is None  # status bar back to Blender's default


def test_unregister_while_in_use_keeps_data_and_reregister_catches_up(blender):
    import blender_addon
    from blender_addon import api

    a, b = make_object("icosphere"), make_object("mixed")
    api.add_surface(a, resolution=2)
    api.add_surface(b, resolution=3, kernel="logistic")
    snaps = {o.name: _snapshot(o) for o in (a, b)}
    surfaces = {o.name: evaluated(o) for o in (a, b)}
    blender_addon.unregister()
    for o in (a, b):
        assert _same_base(o, snaps[o.name])
        assert np.array_equal(evaluated(o), surfaces[o.name])  # last surface still shown
    # edits while the add-on is off: no crash, and never the stale surface: the node
    # group sees the edit and shows the edited base mesh with a warning
    a.data.vertices[3].co.z += 0.3
    a.data.update()
    shown = evaluated(a)
    assert np.array_equal(shown, positions(a.data))
    ((kind, message),) = _warnings(a)
    assert kind == "WARNING" and "out of date" in message
    blender_addon.register()  # catches up with the edit at once
    Pa = evaluated(a)
    assert len(Pa) == len(surfaces[a.name]) and _warnings(a) == []
    assert np.abs(Pa[3] - positions(a.data)[3]).max() <= 1e-6
    assert np.abs(Pa - surfaces[a.name]).max() > 0.05
    assert np.array_equal(evaluated(b), surfaces[b.name])
    b.data.vertices[12].co.z += 0.2  # and live again
    b.data.update()
    assert np.abs(evaluated(b)[12] - positions(b.data)[12]).max() <= 1e-6


def _reload_package():
    """What Reload Scripts does to an add-on: unregister, re-import, register."""
    import blender_addon
    from blender_addon import (api, engine, errors, geometry_nodes, handlers, ids, mesh_io,
                               node_tree, op_add_surface, op_apply, op_rebuild, op_remove, panels,
                               progress, properties, results, settings, stencil_update)

    blender_addon.unregister()
    for module in (ids, errors, settings, progress, node_tree, geometry_nodes, mesh_io,
                   stencil_update, results, engine, handlers, api, properties, panels,
                   op_add_surface, op_apply, op_rebuild, op_remove, blender_addon):
        importlib.reload(module)
    blender_addon.register()


def test_reload_scripts_keeps_modifiers_working(blender):
    import blender_addon
    from .test_register import _menu_draw_funcs, _ours

    obj = make_object("suzanne")
    from blender_addon import api
    api.add_surface(obj, resolution=2)
    snap = _snapshot(obj)
    P = evaluated(obj)
    old = (api.GERBSSyncError, bpy.types.OBJECT_OT_gerbs_add_surface)
    _reload_package()
    from blender_addon import api as api2, engine as engine2
    assert api2.GERBSSyncError is not old[0]  # really re-executed
    assert bpy.types.OBJECT_OT_gerbs_add_surface is not old[1]
    assert _same_base(obj, snap)
    assert np.array_equal(evaluated(obj), P)
    for name in ("depsgraph_update_post", "undo_post", "redo_post", "load_post"):
        assert len(_ours(getattr(bpy.app.handlers, name))) == 1, name
    assert len(_menu_draw_funcs()) == 1
    obj.data.vertices[100].co.x += 0.2  # the reloaded handler keeps it live
    obj.data.update()
    P2 = evaluated(obj)
    assert np.abs(P2[100] - positions(obj.data)[100]).max() <= 1e-6
    assert engine2.get_state(obj, api2.get_modifier(obj)) is not None
    other = make_object("grid")  # and the reloaded operator adds new surfaces
    assert bpy.ops.object.gerbs_add_surface(resolution=2) == {"FINISHED"}
    assert len(evaluated(other)) > len(other.data.vertices)
    blender_addon.unregister()
    blender_addon.register()


def _undo(n=1):
    for _ in range(n):
        assert bpy.ops.ed.undo() == {"FINISHED"}


def _redo(n=1):
    for _ in range(n):
        assert bpy.ops.ed.redo() == {"FINISHED"}


def test_undo_redo_across_add_edit_apply_with_operators(blender):
    from blender_addon import api

    obj = make_object("uv_sphere")
    name = obj.name
    X = positions(obj.data)
    bpy.ops.ed.undo_push(message="start")
    assert bpy.ops.object.gerbs_add_surface(resolution=2) == {"FINISHED"}
    bpy.ops.ed.undo_push(message="added")
    P_added = evaluated(obj)
    obj.data.vertices[10].co.z += 0.3
    obj.data.update()
    P_edited = evaluated(obj)
    bpy.ops.ed.undo_push(message="edited")
    assert bpy.ops.object.gerbs_apply() == {"FINISHED"}
    bpy.ops.ed.undo_push(message="applied")
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 0 and np.abs(positions(obj.data) - P_edited).max() == 0.0

    _undo()  # before apply: modifier back, edited base, edited surface
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 1 and len(obj.data.vertices) == len(X)
    assert np.abs(evaluated(obj) - P_edited).max() <= 1e-6
    _undo()  # before the edit
    obj = bpy.data.objects[name]
    assert np.array_equal(positions(obj.data), X)
    assert np.abs(evaluated(obj) - P_added).max() <= 1e-6
    _undo()  # before add: no modifier, no result object left behind
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 0 and np.array_equal(evaluated(obj), X)

    _redo(2)  # add, edit
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 1 and np.abs(evaluated(obj) - P_edited).max() <= 1e-6
    _redo()  # apply
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 0 and np.abs(positions(obj.data) - P_edited).max() == 0.0
    api.add_surface(obj, resolution=2)  # the applied mesh carries a new surface
    assert len(evaluated(obj)) > len(obj.data.vertices)


def test_undo_redo_across_add_and_remove_with_operators(blender):
    from blender_addon import handlers, ids

    obj = make_object("mixed")
    name = obj.name
    X = positions(obj.data)
    bpy.ops.ed.undo_push(message="start")
    assert bpy.ops.object.gerbs_add_surface(resolution=3, kernel="BFBS") == {"FINISHED"}
    bpy.ops.ed.undo_push(message="added")
    P = evaluated(obj)
    assert bpy.ops.object.gerbs_remove() == {"FINISHED"}
    bpy.ops.ed.undo_push(message="removed")
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 0 and np.array_equal(evaluated(obj), X)
    assert not [o for o in bpy.data.objects if o.get(ids.RESULT_TAG)]  # result cleaned up
    for _ in range(2):
        _undo()  # removed -> added
        obj = bpy.data.objects[name]
        assert len(obj.modifiers) == 1 and np.abs(evaluated(obj) - P).max() <= 1e-6
        obj.data.vertices[5].co.z += 0.1  # live on the restored modifier
        obj.data.update()
        assert np.abs(evaluated(obj)[5] - positions(obj.data)[5]).max() <= 1e-6
        obj.data.vertices[5].co.z -= 0.1
        obj.data.update()
        _redo()  # added -> removed
        obj = bpy.data.objects[name]
        assert len(obj.modifiers) == 0 and np.array_equal(evaluated(obj), X)
    handlers.collect_now()
    _undo(2)  # back to the start: nothing of ours left
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 0 and np.array_equal(positions(obj.data), X)


@pytest.mark.parametrize("settings,match", [
    (dict(alpha=100.0), "cannot be tabulated"),  # untabulable ERBS: refused by the kernel
    # outside the guaranteed box: 1 - F underflows, holes in the cover: refused by
    # BlendingSurface (InvalidParameterError "kernel")
    (dict(gamma=7.389, lam=0.0, sigma=0.0), "holes in the cover"),
])
def test_extreme_kernel_parameters_are_an_error_not_a_crash(blender, settings, match):
    from blender_addon import api
    from blender_addon.api import GERBSSyncError

    obj = make_object("icosphere")
    snap = _snapshot(obj)
    with pytest.raises(GERBSSyncError, match=match):
        api.add_surface(obj, resolution=2, **settings)
    assert np.array_equal(evaluated(obj), snap[0]) and _same_base(obj, snap)
    ((kind, message),) = _warnings(obj)
    assert kind == "ERROR"
    api.set_settings(obj, alpha=1.0, gamma=1.0, lam=0.5, sigma=1.0)  # back in range: live again
    P = evaluated(obj)
    assert len(P) > len(snap[0]) and _warnings(obj) == []
