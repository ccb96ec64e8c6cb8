"""The surface follows time: animated vertices, shape keys, drivers and animated settings;
Blender's own Apply and the exporters bake the surface of the current frame (issue 12, item 2)."""
import bpy
import numpy as np
import pytest
from scipy.spatial import cKDTree

from .helpers import (evaluated, export_and_reimport, fresh_surface, make_object,
                      modifier_input, topology, warnings)

pytestmark = pytest.mark.blender

R = 3


def _assert_current(obj, resolution=R):
    """The evaluated surface equals a fresh build from what the modifier receives now
    (the surface is read first: reading the input toggles the modifier, an update)."""
    P = evaluated(obj)
    # no error or stale warning; a spiky shape key may make the surface cross itself (said)
    assert [w for w in warnings(obj) if "passes through itself" not in w[1]] == []
    X = modifier_input(obj)
    offsets, corners = topology(obj.data)
    assert np.abs(P - fresh_surface(X, offsets, corners, resolution)).max() <= 1e-5
    return P


def _animate_vertex(obj, index, z_by_frame):
    v = obj.data.vertices[index]
    for frame, z in z_by_frame.items():
        v.co.z = z
        v.keyframe_insert("co", index=2, frame=frame)


def test_frame_set_follows_animated_vertices(blender):
    from blender_addon import api

    obj = make_object("icosphere")
    z0 = obj.data.vertices[3].co.z
    _animate_vertex(obj, 3, {1: z0, 10: z0 + 1.5})
    api.add_surface(obj, resolution=R)
    scene = bpy.context.scene
    scene.frame_set(1)
    P1 = _assert_current(obj)
    scene.frame_set(10)
    P10 = _assert_current(obj)
    assert abs(P10[3, 2] - (z0 + 1.5)) <= 1e-6 and np.abs(P10 - P1).max() > 0.5
    scene.frame_set(5)  # in between: the interpolated key
    _assert_current(obj)


def test_frame_set_follows_shape_key_values_and_drivers(blender):
    from blender_addon import api

    obj = make_object("suzanne")
    obj.shape_key_add(name="Basis")
    key = obj.shape_key_add(name="Up")
    for i in range(0, len(key.data), 7):
        key.data[i].co.z += 0.3
    key.value = 0.0
    key.keyframe_insert("value", frame=1)
    key.value = 1.0
    key.keyframe_insert("value", frame=11)
    api.add_surface(obj, resolution=R)
    scene = bpy.context.scene
    surfaces = {}
    for frame in (1, 6, 11):
        scene.frame_set(frame)
        surfaces[frame] = _assert_current(obj)
    assert np.abs(surfaces[11] - surfaces[1]).max() > 0.2
    # a driver: the shape-key value follows a custom property of the scene
    obj.data.shape_keys.animation_data_clear()
    scene["lift"] = 0.25
    fcurve = key.driver_add("value")
    fcurve.driver.type = "AVERAGE"
    var = fcurve.driver.variables.new()
    var.targets[0].id_type = "SCENE"
    var.targets[0].id = scene
    var.targets[0].data_path = '["lift"]'
    bpy.context.view_layer.update()
    P_quarter = _assert_current(obj)
    scene["lift"] = 0.75
    scene.update_tag()
    bpy.context.view_layer.update()
    P_three = _assert_current(obj)
    assert np.abs(P_three - P_quarter).max() > 0.1


def test_frame_set_follows_an_animated_resolution(blender):
    from blender_addon import api

    obj = make_object("grid")
    mod = api.add_surface(obj, resolution=2)
    key = next(item.identifier for item in mod.node_group.interface.items_tree
               if getattr(item, "name", "") == "Resolution")
    mod[key] = 2
    mod.keyframe_insert(f'["{key}"]', frame=1)
    mod[key] = 5
    mod.keyframe_insert(f'["{key}"]', frame=10)
    scene = bpy.context.scene
    counts = {}
    for frame in (1, 10):
        scene.frame_set(frame)
        r = api.get_settings(obj)["resolution"]
        counts[frame] = len(_assert_current(obj, resolution=r))
    assert counts[10] > counts[1]


def _animated_suzanne():
    """Suzanne with vertex 0 keyframed from z0 (frame 1) to z0 + 1 (frame 10); and the
    base positions at frame 10, known without evaluating anything."""
    from .helpers import positions

    obj = make_object("suzanne")
    X10 = positions(obj.data)
    z0 = float(X10[0, 2])
    X10[0, 2] = np.float32(z0 + 1.0)
    _animate_vertex(obj, 0, {1: z0, 10: z0 + 1.0})
    return obj, X10


def test_native_apply_right_after_a_frame_change_bakes_the_current_surface(blender):
    from blender_addon import api

    from .helpers import positions

    obj, X10 = _animated_suzanne()
    offsets, corners = topology(obj.data)
    mod = api.add_surface(obj, resolution=R)
    bpy.context.scene.frame_set(1)
    evaluated(obj)
    bpy.context.scene.frame_set(10)
    obj.animation_data_clear()
    obj.data.animation_data_clear()  # keep the applied mesh from being re-animated
    with bpy.context.temp_override(object=obj, active_object=obj):
        bpy.ops.object.modifier_apply(modifier=mod.name)
    assert np.abs(positions(obj.data) - fresh_surface(X10, offsets, corners, R)).max() <= 1e-5


def _point_sets_equal(P, Q, tol=1e-5):
    """The same points (an exporter splits vertices at flat faces and UV seams, so Q may
    hold some of them more than once)."""
    assert len(Q) >= len(P)
    assert cKDTree(P).query(Q)[0].max() <= tol and cKDTree(Q).query(P)[0].max() <= tol


@pytest.mark.parametrize("ext", [".glb", ".obj"])
def test_export_after_a_frame_change_writes_the_current_surface(blender, tmp_path, ext):
    from blender_addon import api

    from .helpers import positions

    obj, _ = _animated_suzanne()
    api.add_surface(obj, resolution=2)
    bpy.context.scene.frame_set(1)
    P1 = evaluated(obj)
    bpy.context.scene.frame_set(10)
    P10 = _assert_current(obj, resolution=2)
    imported = export_and_reimport(obj, tmp_path / f"frame10{ext}")
    _point_sets_equal(P10, positions(imported.data))
    assert np.abs(P10 - P1).max() > 0.5
