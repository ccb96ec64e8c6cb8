"""No leaks: result objects, their meshes and the node group go when nothing uses them
(issue 12, item 5); the state follows a modifier through a rename (issue 16, item 5)."""
import bpy
import numpy as np
import pytest

from .helpers import evaluated, make_object, positions, warnings

pytestmark = pytest.mark.blender


def _ours():
    from blender_addon import geometry_nodes as gn, ids

    return (sorted(o.name for o in bpy.data.objects if o.get(ids.RESULT_TAG)),
            sorted(m.name for m in bpy.data.meshes if m.get(ids.RESULT_TAG)),
            sorted(g.name for g in bpy.data.node_groups if gn.is_gerbs_group(g)))


def _parts():
    from blender_addon import node_parts

    return sorted(g.name for g in bpy.data.node_groups if node_parts.is_part(g))


def test_deleting_the_hidden_result_by_hand_leaves_no_orphans(blender):
    from blender_addon import api
    from blender_addon import geometry_nodes as gn

    obj = make_object("icosphere")
    mod = api.add_surface(obj, resolution=2)
    P = evaluated(obj)
    for _ in range(3):
        bpy.data.objects.remove(gn.get_result(mod))
        P2 = evaluated(obj)  # a new result is made within the update
        assert np.abs(P2 - P).max() <= 1e-6 and warnings(obj) == []
        objects, meshes, groups = _ours()
        assert len(objects) == 1 and len(meshes) == 1 and len(groups) == 1
    assert not [m for m in bpy.data.meshes if m.users == 0]


@pytest.mark.parametrize("how", ["api", "operator", "native remove", "native apply",
                                 "delete object"])
def test_the_last_modifier_gone_takes_results_meshes_and_group_with_it(blender, how):
    from blender_addon import api

    a, b = make_object("icosphere"), make_object("grid")
    api.add_surface(a, resolution=2)
    mod = api.add_surface(b, resolution=2)
    assert [len(x) for x in _ours()] == [2, 2, 1]
    api.remove(a)
    assert [len(x) for x in _ours()] == [1, 1, 1]  # the group is still used by b
    parts = _parts()
    assert len(parts) > 1 and all(bpy.data.node_groups[p].users > 0 for p in parts)
    bpy.context.view_layer.objects.active = b
    if how == "api":
        api.remove(b)
    elif how == "operator":
        assert bpy.ops.object.gerbs_remove() == {"FINISHED"}
    elif how == "native remove":
        bpy.ops.object.modifier_remove(modifier=mod.name)
    elif how == "native apply":
        bpy.ops.object.modifier_apply(modifier=mod.name)
    else:
        bpy.data.objects.remove(b)
    bpy.context.view_layer.update()
    assert _ours() == ([], [], []) and _parts() == []  # the group's parts went with it
    assert not [m for m in bpy.data.meshes if m.users == 0 and m.name != "Grid"]


def test_renaming_the_modifier_or_object_keeps_the_state(blender):
    from blender_addon import api, engine

    obj = make_object("suzanne")
    mod = api.add_surface(obj, resolution=3, rest="bound")  # edits: the linear fast path
    st = engine.get_state(obj, mod)
    before = dict(engine.stats)
    mod.name = "Smooth it"
    obj.name = "Monkey"
    obj.data.vertices[3].co.z += 0.1
    obj.data.update()
    P = evaluated(obj)
    assert engine.get_state(obj, mod) is st  # same state: only W @ X ran
    assert engine.stats["rebuilt"] == before.get("rebuilt", 0)
    assert np.abs(P[3] - positions(obj.data)[3]).max() <= 1e-6
