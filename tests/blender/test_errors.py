"""Invalid meshes: a clear error naming problem and indices; the base mesh untouched."""
import bpy
import numpy as np
import pytest

from .helpers import evaluated, link_object, make_object, positions, topology

pytestmark = pytest.mark.blender

NON_MANIFOLD = ([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)],
                [(0, 1, 2), (1, 0, 3), (0, 1, 4)])  # edge (0, 1) in three faces
LOOSE_VERTEX = ([(0, 0, 0), (1, 0, 0), (0, 1, 0), (5, 5, 5)], [(0, 1, 2)])
DEGENERATE = ([(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0)], [(0, 1, 2), (0, 2, 3)])


@pytest.mark.parametrize("mesh,problem,index", [
    (NON_MANIFOLD, "non_manifold_edge", None),
    (LOOSE_VERTEX, "unused_vertex", 3),
    (DEGENERATE, "degenerate", 0),
])
def test_invalid_mesh_reports_and_leaves_base_untouched(blender, mesh, problem, index):
    from blender_addon import api
    from blender_addon.api import GERBSSyncError

    obj = link_object("bad", *mesh)
    X = positions(obj.data)
    offsets, corners = topology(obj.data)
    with pytest.raises(GERBSSyncError, match=problem) as info:
        api.add_surface(obj, resolution=2)
    if index is not None:
        assert f"[{index}" in str(info.value)
    P = evaluated(obj)
    (warning,) = obj.modifiers[0].node_warnings  # shown in the modifier panel
    assert problem in warning.message and warning.type == "ERROR"
    assert np.array_equal(P, X)  # modifier passes the base mesh through
    assert np.array_equal(positions(obj.data), X)
    o2, c2 = topology(obj.data)
    assert np.array_equal(o2, offsets) and np.array_equal(c2, corners)


def test_operator_reports_error_in_background(blender):
    obj = link_object("bad", *NON_MANIFOLD)
    X = positions(obj.data)
    with pytest.raises(RuntimeError, match="non_manifold_edge"):  # ERROR report raises headless
        bpy.ops.object.gerbs_add_surface(resolution=2)
    assert np.array_equal(positions(obj.data), X)


def test_error_clears_when_mesh_is_fixed_live(blender):
    from blender_addon import api
    from blender_addon.api import GERBSSyncError

    obj = link_object("bad", *LOOSE_VERTEX)
    with pytest.raises(GERBSSyncError):
        api.add_surface(obj, resolution=2)
    obj.data.vertices[3].select = True
    import bmesh
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    bmesh.ops.delete(bm, geom=[bm.verts[3]], context="VERTS")
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()
    P = evaluated(obj)
    assert len(P) == 6 and api.status(obj)["error"] == ""
    assert not obj.modifiers[0].node_warnings


def test_bad_settings_are_refused(blender):
    from blender_addon import api

    obj = make_object("grid")
    with pytest.raises(ValueError, match="colour: unknown GERBS setting"):
        api.add_surface(obj, resolution=2, colour="red")
    with pytest.raises(ValueError, match="boundary"):
        api.add_surface(obj, boundary="bogus")
    assert len(obj.modifiers) == 0


def test_too_large_resolution_is_an_error_not_a_crash(blender):
    from blender_addon import api
    from blender_addon.api import GERBSSyncError

    obj = make_object("suzanne")
    X = positions(obj.data)
    with pytest.raises(GERBSSyncError, match="memory"):
        api.add_surface(obj, resolution=64, memory_budget=1e6)
    assert np.array_equal(evaluated(obj), X)
