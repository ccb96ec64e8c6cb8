"""Registration: symmetric, idempotent, leaves no handlers or classes behind."""
import bpy
import pytest

pytestmark = pytest.mark.blender


def _ours(lst):
    return [f for f in lst if getattr(f, "__module__", "").startswith("blender_addon")]


def _menu_draw_funcs():
    menu = getattr(bpy.types, "OBJECT_MT_modifier_add_generate")
    return [f for f in menu._dyn_ui_initialize() if getattr(f, "__module__", "").startswith("blender_addon")]


def test_register_unregister_twice(blender):
    import blender_addon

    for _ in range(2):
        blender_addon.unregister()
        blender_addon.unregister()  # second call is a no-op
        assert not hasattr(bpy.types, "OBJECT_OT_gerbs_add_surface")
        assert not hasattr(bpy.types.Scene, "gerbs")
        assert _ours(bpy.app.handlers.depsgraph_update_post) == []
        assert _ours(bpy.app.handlers.load_post) == []
        assert _menu_draw_funcs() == []
        blender_addon.register()
        blender_addon.register()  # re-register: no duplicates
        assert hasattr(bpy.types, "OBJECT_OT_gerbs_add_surface")
        for name in ("depsgraph_update_post", "undo_post", "redo_post", "load_post"):
            assert len(_ours(getattr(bpy.app.handlers, name))) == 1, name
        assert len(_menu_draw_funcs()) == 1


def test_menu_entry_adds_modifier_via_operator(blender):
    from .helpers import make_object

    obj = make_object("grid")
    assert bpy.ops.object.gerbs_add_surface.poll()
    assert bpy.ops.object.gerbs_add_surface(resolution=2) == {"FINISHED"}
    mod = obj.modifiers[-1]
    assert mod.type == "NODES" and mod.name == "GERBS Blending Surface"
    names = {item.name for item in mod.node_group.interface.items_tree}
    for label in ("Kernel", "Alpha", "Lambda", "Resolution", "Rest Shape", "Boundary",
                  "Use Custom Normals"):
        assert label in names


@pytest.mark.parametrize("op, words", [
    ("gerbs_remove", "'Cube' has no GERBS Blending Surface modifier"),
    ("gerbs_rebuild", "'Cube' has no GERBS Blending Surface modifier"),
    ("gerbs_apply", "'Cube' has no GERBS Blending Surface modifier"),
    ("gerbs_select_problem", "names vertices, edges or faces"),
])
def test_an_operator_that_cannot_run_says_why(blender, op, words):
    """A newcomer's walk (2026-12-07): gerbs_remove on an object without the modifier said
    only Blender's "poll() failed, context is incorrect"."""
    bpy.ops.mesh.primitive_cube_add()
    with pytest.raises(RuntimeError, match=words) as info:
        getattr(bpy.ops.object, op)()
    assert "context is incorrect" not in str(info.value)


def test_add_and_apply_say_what_is_missing(blender):
    from blender_addon import api

    bpy.ops.object.empty_add()
    with pytest.raises(RuntimeError, match="'Empty' is not a mesh"):
        bpy.ops.object.gerbs_add_surface()
    bpy.ops.mesh.primitive_cube_add()
    api.add_surface(bpy.context.active_object, resolution=2)
    bpy.ops.object.mode_set(mode="EDIT")
    with pytest.raises(RuntimeError, match="Only in Object Mode"):
        bpy.ops.object.gerbs_apply()
    bpy.ops.object.mode_set(mode="OBJECT")
    assert bpy.ops.object.gerbs_apply() == {"FINISHED"}


def test_unregister_with_modifiers_keeps_objects_and_surface(blender):
    import blender_addon
    from blender_addon import api
    from .helpers import evaluated, make_object

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=2)
    before = evaluated(obj)
    blender_addon.unregister()
    after = evaluated(obj)  # the GN modifier still shows the last surface
    assert after.shape == before.shape and abs(after - before).max() == 0.0
    blender_addon.register()
    obj.data.vertices[0].co.z += 0.25
    obj.data.update()
    assert abs(evaluated(obj) - before).max() > 0.01  # live again after re-registering


def test_reload_without_unregister_leaves_one_of_everything(blender):
    """Reload Scripts re-imports the package while the old copy is registered."""
    import importlib

    import blender_addon

    from blender_addon import handlers, op_add_surface, panels, properties

    for module in (properties, panels, handlers, op_add_surface, blender_addon):
        importlib.reload(module)  # new class and function objects; the old ones stay registered
    blender_addon.register()
    assert bpy.types.OBJECT_OT_gerbs_add_surface is not None
    for name in ("depsgraph_update_post", "undo_post", "redo_post", "load_post"):
        assert len(_ours(getattr(bpy.app.handlers, name))) == 1, name
    assert len(_menu_draw_funcs()) == 1
    blender_addon.unregister()
    assert not hasattr(bpy.types, "OBJECT_OT_gerbs_add_surface")
    assert _menu_draw_funcs() == [] and _ours(bpy.app.handlers.depsgraph_update_post) == []
    blender_addon.register()
