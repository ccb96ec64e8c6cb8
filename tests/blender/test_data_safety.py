"""The add-on writes only its own data: whatever the modifier's hidden inputs point at,
whatever the build gives, the user's meshes are never overwritten and nothing that is not
a surface is shown, applied or exported."""
import bpy
import numpy as np
import pytest

from .helpers import base_positions, evaluated

pytestmark = pytest.mark.blender


def _gerbs_marks(mesh) -> list:
    """What the add-on would have left on `mesh` by writing a result into it."""
    from blender_addon import ids

    names = [a.name for a in mesh.attributes if a.name.startswith(".gerbs")]
    return names + [k for k in (ids.RECORD_STAMP, ids.RESULT_TAG) if k in mesh]


def _cube_with_surface(resolution=3, **settings):
    from blender_addon import api

    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.active_object
    mod = api.add_surface(cube, resolution=resolution, **settings)
    return cube, mod


# 8 vertices, 12 edges, 6 quads at resolution 3
CUBE_R3 = 8 + 12 * 2 + 6 * 4


@pytest.mark.parametrize("how", ["remap_object", "remap_mesh", "set_input"])
def test_a_result_input_pointing_at_a_users_object_never_writes_it(blender, how):
    """Remap Users of the hidden result onto the user's torus (object or mesh), or a script
    setting the hidden input: the torus keeps its mesh, the modifier gets a fresh result of
    its own and shows the surface (before: the torus's 576 vertices were overwritten)."""
    from blender_addon import api, ids
    from blender_addon import geometry_nodes as gn

    bpy.ops.mesh.primitive_torus_add(location=(4, 0, 0))
    torus = bpy.context.active_object
    T = base_positions(torus)
    cube, mod = _cube_with_surface()
    result = gn.get_result(mod)
    if how == "remap_object":
        result.user_remap(torus)
    elif how == "remap_mesh":
        result.data.user_remap(torus.data)
        assert gn.get_result(mod).data == torus.data
    else:
        gn.set_result(mod, torus)
    cube.data.vertices[0].co.z += 0.1
    cube.data.update()
    P = evaluated(cube)
    assert len(torus.data.vertices) == 576 and np.array_equal(base_positions(torus), T)
    assert _gerbs_marks(torus.data) == []
    own = gn.get_result(mod)
    assert own not in (torus, None) and own.get(ids.RESULT_TAG) and own.data != torus.data
    assert len(P) == CUBE_R3 and api.status(cube)["error"] == ""
    assert P[0, 2] == pytest.approx(base_positions(cube)[0, 2])  # the moved cube's surface


def test_a_result_input_pointing_at_the_base_object_never_writes_its_mesh(blender):
    from blender_addon import api
    from blender_addon import geometry_nodes as gn

    cube, mod = _cube_with_surface(resolution=3, render_resolution=2)
    X = base_positions(cube)
    for render in (False, True):
        gn.set_result(mod, cube, render)
    cube.update_tag()
    P = evaluated(cube)
    assert len(cube.data.vertices) == 8 and np.array_equal(base_positions(cube), X)
    assert _gerbs_marks(cube.data) == []
    assert len(P) == CUBE_R3 and api.status(cube)["error"] == ""
    assert cube not in (gn.get_result(mod), gn.get_result(mod, True))
    api.update(cube, force=True)  # a Rebuild writes the fresh results only, too
    assert len(cube.data.vertices) == 8 and _gerbs_marks(cube.data) == []


def test_a_result_mesh_another_object_uses_is_not_written(blender):
    """A user object made from the hidden result's mesh (e.g. to keep a copy of the surface)
    keeps it: the add-on makes a new result instead of changing a mesh someone else shows."""
    from blender_addon import geometry_nodes as gn

    cube, mod = _cube_with_surface()
    kept = bpy.data.objects.new("Kept", gn.get_result(mod).data)
    bpy.context.scene.collection.objects.link(kept)
    K = base_positions(kept)
    cube.data.vertices[0].co.z += 0.1
    cube.data.update()
    P = evaluated(cube)
    assert np.array_equal(base_positions(kept), K)
    assert gn.get_result(mod).data != kept.data
    assert np.abs(P - K).max() > 0.01  # the cube shows its new surface


# --- a surface beyond float32 --------------------------------------------------------

def _all_finite(P) -> bool:
    return bool(np.all(np.isfinite(P)))


def test_a_surface_beyond_float32_is_an_error_and_never_applied(blender):
    """Cube corners at +-3e38 (finite float32): its rounder surface overshoots float32's
    range. The build is refused with the "surface is not finite" error, the base mesh passes
    through, and Apply refuses (before: 54 infinite points shown, applied into the mesh)."""
    import mathutils

    from blender_addon import api

    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.active_object
    cube.data.transform(mathutils.Matrix.Scale(3e38, 4))
    cube.data.update()
    X = base_positions(cube)
    with pytest.raises(api.GERBSSyncError, match="surface is not finite.*single precision"):
        api.add_surface(cube, resolution=4)
    P = evaluated(cube)
    assert np.array_equal(P, X) and _all_finite(P)
    assert "not finite" in api.status(cube)["error"]
    with pytest.raises(api.GERBSSyncError, match="not finite"):
        api.apply(cube)
    assert len(cube.modifiers) == 1 and np.array_equal(base_positions(cube), X)


def test_a_bound_surface_moved_beyond_float32_never_shows_infinite_points(blender):
    """Rest Shape Bound updates linearly (the whole product, or only the moved vertices'
    columns): an edit that takes the surface beyond float32 never writes inf."""
    import mathutils

    from blender_addon import api

    cube, _ = _cube_with_surface(resolution=4, rest="bound")
    cube.data.transform(mathutils.Matrix.Scale(3e38, 4))  # the whole product
    cube.data.update()
    P = evaluated(cube)
    assert _all_finite(P) and np.array_equal(P, base_positions(cube))
    assert "not finite" in api.status(cube)["error"]

    bpy.ops.mesh.primitive_grid_add(x_subdivisions=10, y_subdivisions=10, size=2)
    grid = bpy.context.active_object
    api.add_surface(grid, resolution=3, rest="bound")
    for i in (44, 45, 54, 55):  # 4 of 121 vertices: a partial update
        grid.data.vertices[i].co.z = 3.39e38
    grid.data.update()
    assert _all_finite(evaluated(grid))


# --- Blender's own Apply of a modifier that passes its input on --------------------------

@pytest.mark.parametrize("why", ["invalid_mesh", "live_update_off", "convert"])
def test_blenders_own_apply_of_a_pass_through_modifier_gives_the_mesh_back_as_it_was(blender,
                                                                                     why):
    """The pass-through carries the channel (.gerbs_in_*) for the add-on to read; Blender's
    Apply / Convert to Mesh baked it into the user's mesh (before: .gerbs_in_face_size,
    .gerbs_in_position, .gerbs_in_record_0/1 stayed, saved with the file)."""
    from blender_addon import api

    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.active_object
    before = sorted(a.name for a in cube.data.attributes)
    if why == "invalid_mesh":
        cube.data.vertices[0].co.x = float("nan")
        cube.data.update()
        api.add_surface(cube, resolution=2, raise_errors=False)
        assert "non_finite" in api.status(cube)["error"]
    else:
        api.add_surface(cube, resolution=2)
        bpy.context.scene.gerbs.live_update = False
        cube.data.vertices[0].co.z += 0.5
        cube.data.update()
    X = base_positions(cube)
    P = evaluated(cube)
    assert len(P) == 8 and np.array_equal(P, X, equal_nan=True)  # passed through
    with bpy.context.temp_override(object=cube, active_object=cube, selected_objects=[cube]):
        if why == "convert":
            bpy.ops.object.convert(target="MESH")
        else:
            bpy.ops.object.modifier_apply(modifier=cube.modifiers[0].name)
    bpy.context.view_layer.update()
    assert len(cube.modifiers) == 0
    assert sorted(a.name for a in cube.data.attributes) == before
    assert np.array_equal(base_positions(cube), X, equal_nan=True)
