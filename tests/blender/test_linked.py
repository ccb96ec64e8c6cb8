"""Objects linked from a library are read-only to the add-on: it never writes their
modifier, result or mesh; the surface saved in the library shows while its record is
fresh, else the base mesh with a status saying why. Library overrides are local and
update like any object, without writing the library's data."""
import bpy
import numpy as np
import pytest

from .helpers import evaluated, make_object

pytestmark = pytest.mark.blender

R = 2
SUZANNE_R2 = 1980  # Suzanne's surface points at resolution 2 (507 vertices)


def _library(path, stale: bool = False):
    """Save to `path` Suzanne with a GERBS surface in the collection "Asset" (`stale`: its
    mesh edited with the add-on off, so the saved surface is out of date), then start an
    empty file. Returns the result mesh's stamp as saved."""
    import blender_addon
    from blender_addon import api, ids
    from blender_addon import geometry_nodes as gn

    obj = make_object("suzanne")
    obj.name = "Suzanne"
    mod = api.add_surface(obj, resolution=R)
    assert len(evaluated(obj)) == SUZANNE_R2
    coll = bpy.data.collections.new("Asset")
    bpy.context.scene.collection.children.link(coll)
    bpy.context.scene.collection.objects.unlink(obj)
    coll.objects.link(obj)
    stamp = gn.get_result(mod).data[ids.RECORD_STAMP]
    blender_addon.unregister()
    try:
        if stale:
            obj.data.vertices[0].co.z += 0.3
            obj.data.update()
        bpy.ops.wm.save_as_mainfile(filepath=str(path))
        bpy.ops.wm.read_factory_settings(use_empty=True)
    finally:
        blender_addon.register()
    return stamp


def _instance_counts(name):
    """Vertex counts of the evaluated instances of object `name` (a collection instance)."""
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    return [len(i.object.data.vertices) for i in dg.object_instances
            if i.is_instance and i.object.name == name]


def _library_result(obj):
    from blender_addon import geometry_nodes as gn

    res = gn.get_result(obj.modifiers[0])
    assert res.library is not None and res.data.library is not None
    return res


@pytest.mark.parametrize("how", ["collection_instance", "libraries_load"])
def test_a_linked_object_shows_its_saved_surface_and_nothing_is_written(blender, tmp_path, how):
    """Before: the linked instance showed its base mesh (507 vertices) once the add-on was
    enabled, and the sync rebuilt into the library's result mesh (its stamp changed)."""
    from blender_addon import api, ids

    lib = tmp_path / "lib.blend"
    stamp = _library(lib)
    if how == "collection_instance":
        bpy.ops.wm.link(directory=f"{lib}/Collection/", filename="Asset")
    else:
        with bpy.data.libraries.load(str(lib), link=True) as (_, dst):
            dst.objects = ["Suzanne"]
        bpy.context.scene.collection.objects.link(dst.objects[0])
    obj = bpy.data.objects["Suzanne"]
    assert obj.library is not None
    res = _library_result(obj)
    names = {k: obj.modifiers[0][k] for k in obj.modifiers[0].keys()
             if isinstance(obj.modifiers[0][k], str)}
    if how == "collection_instance":
        assert _instance_counts("Suzanne") == [SUZANNE_R2]
    else:
        assert len(evaluated(obj)) == SUZANNE_R2
    api.update(obj)  # a sync says all is well, and writes nothing
    assert api.status(obj)["error"] == ""
    assert res.data[ids.RECORD_STAMP] == stamp and len(res.data.vertices) == SUZANNE_R2
    assert {k: obj.modifiers[0][k] for k in names} == names  # error, names, warning lines
    for change in (lambda: api.set_settings(obj, resolution=3), lambda: api.remove(obj),
                   lambda: api.apply(obj)):
        with pytest.raises(api.OperationError, match="linked from the library.*read-only"):
            change()
    assert api.get_settings(obj)["resolution"] == R and len(obj.modifiers) == 1


def test_a_linked_object_whose_saved_surface_is_stale_says_why(blender, tmp_path):
    from blender_addon import api, handlers, ids
    from blender_addon import geometry_nodes as gn

    lib = tmp_path / "lib.blend"
    stamp = _library(lib, stale=True)
    bpy.ops.wm.link(directory=f"{lib}/Collection/", filename="Asset")
    obj = bpy.data.objects["Suzanne"]
    res = _library_result(obj)
    assert _instance_counts("Suzanne") == [507]  # the base mesh, never the stale surface
    out = api.update(obj, raise_errors=False)
    assert [r.status for r in out] == ["error"]
    error = api.status(obj)["error"]
    assert "linked from the library" in error and "base mesh is shown" in error
    assert "linked from the library" in (handlers.status_message or "")
    assert res.data[ids.RECORD_STAMP] == stamp and gn.get_error(obj.modifiers[0]) == ""
    assert _instance_counts("Suzanne") == [507]


def test_a_library_override_updates_without_writing_the_library(blender, tmp_path):
    """An override (local) changes and rebuilds; the library's result and the linked
    original are never written, also when the file is saved and reopened."""
    from blender_addon import api, ids

    lib = tmp_path / "lib.blend"
    stamp = _library(lib)
    bpy.ops.wm.link(directory=f"{lib}/Collection/", filename="Asset")
    bpy.ops.object.make_override_library()
    (over,) = [o for o in bpy.data.objects if o.override_library is not None and o.type == "MESH"]
    (linked,) = [o for o in bpy.data.objects if o.library is not None and o.type == "MESH"
                 and not o.get(ids.RESULT_TAG)]
    lib_res = _library_result(linked)
    assert len(evaluated(over)) == SUZANNE_R2
    api.set_settings(over, resolution=3)
    P3 = evaluated(over)
    assert len(P3) > SUZANNE_R2 and api.status(over)["error"] == ""
    assert lib_res.data[ids.RECORD_STAMP] == stamp
    main = tmp_path / "main.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(main))
    bpy.ops.wm.open_mainfile(filepath=str(main))
    (over,) = [o for o in bpy.data.objects if o.override_library is not None and o.type == "MESH"]
    (linked,) = [o for o in bpy.data.objects if o.library is not None and o.type == "MESH"
                 and not o.get(ids.RESULT_TAG)]
    assert np.array_equal(evaluated(over), P3) and api.get_settings(over)["resolution"] == 3
    assert _library_result(linked).data[ids.RECORD_STAMP] == stamp
