"""Save/reload, opening without the add-on, and export through Blender's glTF/OBJ."""
import bpy
import numpy as np
import pytest
from scipy.spatial import cKDTree

from .helpers import evaluated, evaluated_triangles, make_object, positions, topology

pytestmark = pytest.mark.blender


def test_save_reload_keeps_settings_and_surface(blender, tmp_path):
    from blender_addon import api

    obj = make_object("suzanne")
    api.add_surface(obj, resolution=3, kernel="logistic", degree=3, boundary="straighten")
    name, P = obj.name, evaluated(obj)
    path = tmp_path / "gerbs.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=str(path))
    obj = bpy.data.objects[name]
    settings = api.get_settings(obj)
    assert (settings["resolution"], settings["kernel"], settings["degree"], settings["boundary"]) \
        == (3, "logistic", 3, "straighten")
    assert np.abs(evaluated(obj) - P).max() == 0.0
    # caches were rebuilt on load: live update works
    obj.data.vertices[0].co.z += 0.2
    obj.data.update()
    P2 = evaluated(obj)
    assert np.abs(P2[0] - positions(obj.data)[0]).max() <= 1e-6 and np.abs(P2 - P).max() > 0.01


def test_open_file_without_addon_keeps_base_mesh_and_surface(blender, tmp_path):
    import blender_addon
    from blender_addon import api

    obj = make_object("mixed")
    name, X = obj.name, positions(obj.data)
    offsets, corners = topology(obj.data)
    api.add_surface(obj, resolution=3)
    P = evaluated(obj)
    path = tmp_path / "gerbs.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    blender_addon.unregister()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=str(path))
    obj = bpy.data.objects[name]
    assert np.array_equal(positions(obj.data), X)
    o2, c2 = topology(obj.data)
    assert np.array_equal(o2, offsets) and np.array_equal(c2, corners)
    assert np.abs(evaluated(obj) - P).max() == 0.0  # the saved result object still shows
    obj.modifiers[0].show_viewport = False
    assert np.array_equal(evaluated(obj), X)
    blender_addon.register()  # (the fixture unregisters)


def _canonical(tris):
    """Rotate each triangle to start at its smallest index, then sort the rows."""
    k = np.argmin(tris, axis=1)
    rolled = np.stack([tris[np.arange(len(tris)), (k + j) % 3] for j in range(3)], axis=1)
    return rolled[np.lexsort(rolled.T[::-1])]


def _same_geometry(P, T, Q, U, tol=1e-5):
    """Same point sets and the same triangles, up to `tol`, point order and triangle rotation.

    Points closer than `tol` (Suzanne has coincident vertices where the eyes touch the
    head) are one class: triangles are compared as triples of classes."""
    assert P.shape == Q.shape and T.shape == U.shape
    tree = cKDTree(P)
    d, idx = tree.query(Q)
    assert d.max() <= tol
    cls = np.array([min(group) for group in tree.query_ball_point(P, tol)])
    assert np.array_equal(np.bincount(cls[idx], minlength=len(P)), np.bincount(cls, minlength=len(P)))
    assert np.array_equal(_canonical(cls[T]), _canonical(cls[idx][U]))


@pytest.mark.parametrize("ext", [".glb", ".obj"])
def test_export_writes_surface_and_reimports_identically(blender, tmp_path, ext):
    from blender_addon import api

    obj = make_object("suzanne")
    api.add_surface(obj, resolution=2)
    P, T = evaluated(obj), evaluated_triangles(obj)
    path = tmp_path / f"surface{ext}"
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    if ext == ".glb":
        bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", use_selection=True,
                                  export_apply=True)
    else:
        bpy.ops.wm.obj_export(filepath=str(path), export_selected_objects=True,
                              apply_modifiers=True, export_materials=False)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if ext == ".glb":
        bpy.ops.import_scene.gltf(filepath=str(path), merge_vertices=True)
    else:
        bpy.ops.wm.obj_import(filepath=str(path))
    (imported,) = [o for o in bpy.data.objects if o.type == "MESH"]
    Q = positions(imported.data)
    loops = np.empty(len(imported.data.loops), dtype=np.int32)
    imported.data.loops.foreach_get("vertex_index", loops)
    _same_geometry(P, T, Q, loops.reshape(-1, 3))
