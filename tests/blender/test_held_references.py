"""Held references stay valid: the add-on never reallocates the user's mesh (issue 12, item 1).

A Python read of an original mesh's positions inside a depsgraph handler
un-shares them from the evaluated copy, and a ``MeshVertex`` the user holds then
points at the evaluated copy's array: the edits go there and are lost (the
vertex moved 0.005 instead of 0.15 in the measured case), later writes corrupt
memory. The add-on reads only evaluated data.
"""
import bmesh
import bpy
import numpy as np
import pytest

from .helpers import evaluated, fresh_surface, make_object, positions, topology, warnings

pytestmark = pytest.mark.blender

# 10 steps of a drag, each a full update of the surface (Rest Shape Follow rebuilds): a
# reallocation shows at the first one; 30 steps cost ~100 s of the suite since the fairing
# (gerbs_core.mesh.fairing) made Suzanne's build ~5x dearer
STEPS, STEP = 10, 0.005


def _expected_z(z0: float) -> float:
    """The float32 value after STEPS times ``co.z += STEP`` (each sum rounded to float32)."""
    z = np.float32(z0)
    for _ in range(STEPS):
        z = np.float32(float(z) + STEP)
    return float(z)


def _check_surface(obj, vertex, z):
    """No error, the final mesh is the surface, it passes through the moved vertex and
    equals a fresh build of the current mesh."""
    from blender_addon import api

    assert api.status(obj)["error"] == "" and warnings(obj) == []
    P = evaluated(obj)
    X = positions(obj.data)
    offsets, corners = topology(obj.data)
    assert X[vertex, 2] == np.float32(z)
    assert len(P) > len(X) and np.abs(P[vertex] - X[vertex]).max() <= 1e-6
    assert np.abs(P - fresh_surface(X, offsets, corners, 3)).max() <= 1e-5


@pytest.mark.parametrize("kind,vertex", [("suzanne", 0), ("icosphere", 5)])
def test_held_vertex_drag_in_object_mode(blender, kind, vertex):
    from blender_addon import api

    obj = make_object(kind)
    api.add_surface(obj, resolution=3)
    v = obj.data.vertices[vertex]  # held across all updates
    loop = obj.data.loops[7]
    loop_vertex = loop.vertex_index
    z = _expected_z(v.co.z)
    for _ in range(STEPS):
        v.co.z += STEP
        bpy.context.view_layer.update()
        assert api.status(obj)["error"] == ""
    assert v.co.z == z and obj.data.vertices[vertex].co.z == z  # nothing lost
    assert loop.vertex_index == loop_vertex == obj.data.loops[7].vertex_index
    assert not obj.data.validate(verbose=False)  # no write landed in other data
    _check_surface(obj, vertex, z)


def test_foreach_set_writes_between_updates_and_held_drags_between_them(blender):
    """A second script deforms the mesh with foreach_set between updates; between its
    writes a held reference drags a vertex. Every write is kept exactly and the surface
    follows each one. The reference is taken after the script's last write: Blender
    itself may reallocate an array that foreach_set writes (its API docs: do not keep
    references to data while modifying its container), with or without this add-on."""
    from blender_addon import api

    obj = make_object("suzanne")
    api.add_surface(obj, resolution=3)
    n = len(obj.data.vertices)
    co = np.empty(3 * n, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)  # the script's own copy, taken once
    for k in range(3):
        co[3::3] += np.float32(0.01)  # every vertex moves in x
        obj.data.vertices.foreach_set("co", co)
        obj.data.update()
        bpy.context.view_layer.update()
        assert api.status(obj)["error"] == ""
        v = obj.data.vertices[k]  # held across the drag
        z = float(co[3 * k + 2])
        for _ in range(10):
            v.co.z += STEP
            z = float(np.float32(z + STEP))
            bpy.context.view_layer.update()
            assert api.status(obj)["error"] == ""
        assert v.co.z == z
        co[3 * k + 2] = z  # the script learns about the drag
        _check_surface(obj, k, z)
    assert np.array_equal(positions(obj.data).astype(np.float32).ravel(), co)


def test_held_bmesh_vertex_drag_in_edit_mode(blender):
    from blender_addon import api

    obj = make_object("suzanne")
    api.add_surface(obj, resolution=3)
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    v = bm.verts[0]  # held across all updates
    z = _expected_z(v.co.z)
    for _ in range(STEPS):
        v.co.z += STEP
        bmesh.update_edit_mesh(obj.data)
        bpy.context.view_layer.update()
        assert api.status(obj)["error"] == ""
        P = evaluated(obj)  # the surface while editing passes through the moved vertex
        assert abs(P[0, 2] - v.co.z) <= 1e-6
    assert v.co.z == z
    bpy.ops.object.mode_set(mode="OBJECT")
    _check_surface(obj, 0, z)


def _pointer(obj, k: int) -> int:
    return obj.data.vertices[k].as_pointer()  # a fresh access, as scripts make them


def test_syncs_that_change_nothing_and_rebuilds_leave_the_arrays_where_they_are(blender):
    """api.update (a sync that finds nothing to do) and api.update(force=True) (a rebuild)
    tag nothing of the base object: a tag would make Blender share the mesh's arrays with
    a fresh evaluated copy, and the script's next access of ``mesh.vertices`` would move
    them (copy-on-write), leaving a held vertex pointing at freed memory. Found by a
    newcomer's script: after two api.update calls a held vertex read (0, 1e-45, 6e-45) on
    the Cube and a write through it was lost. The control shows the check catches it: a tag
    of the object, then the same evaluation and access, moves the array."""
    from blender_addon import api

    obj = make_object("suzanne")
    api.add_surface(obj, resolution=2)
    v = obj.data.vertices[5]
    where = v.as_pointer()
    for force in (False, False, True, True, False):
        api.update(obj, force=force)
        bpy.context.view_layer.update()
        assert _pointer(obj, 0) and _pointer(obj, 5) == where
    assert api.status(obj)["error"] == ""
    z = float(np.float32(v.co.z + 1.0))
    v.co.z += 1.0  # through the held reference: kept
    bpy.context.view_layer.update()
    assert obj.data.vertices[5].co.z == z
    assert np.abs(evaluated(obj)[5] - positions(obj.data)[5]).max() <= 1e-6
    # control: what the removed tags did
    moved = []
    for _ in range(2):
        obj.update_tag()
        bpy.context.view_layer.update()
        moved.append(_pointer(obj, 5) != where)
    assert any(moved)
