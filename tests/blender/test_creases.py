"""Creases through the modifier (issue 13 item 1): Blender's crease_edge / crease_vert
attributes of the evaluated mesh reach the core; against Subdivision Surface."""
import bmesh
import bpy
import numpy as np
import pytest

from .helpers import base_positions, evaluated

pytestmark = pytest.mark.blender


def _cube_distance(S, h=1.0):
    inside = np.minimum(np.abs(S + h), np.abs(S - h)).min(axis=1)
    outside = np.linalg.norm(np.maximum(np.abs(S) - h, 0.0), axis=1)
    return np.where(outside > 0, outside, inside)


def _set_creases(mesh, name, domain, values):
    """What a user does: write the crease attribute of the original mesh."""
    attr = mesh.attributes.get(name) or mesh.attributes.new(name, "FLOAT", domain)
    attr.data.foreach_set("value", np.asarray(values, dtype=np.float32))
    mesh.update()


def test_fully_creased_cube_stays_the_cube_like_subdivision_surface(blender):
    from blender_addon import api

    bpy.ops.mesh.primitive_cube_add(size=2.0)
    obj = bpy.context.active_object
    _set_creases(obj.data, "crease_edge", "EDGE", np.ones(len(obj.data.edges)))
    api.add_surface(obj, resolution=6)
    P = evaluated(obj)
    # Blender's own Catmull-Clark with the same creases, on a copy of the same mesh
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(0, 0, 0))
    ref = bpy.context.active_object
    _set_creases(ref.data, "crease_edge", "EDGE", np.ones(len(ref.data.edges)))
    sub = ref.modifiers.new("Subdivision", "SUBSURF")
    sub.levels = 3
    Q = evaluated(ref)
    print(f"fully creased cube: GERBS max distance {_cube_distance(P).max():.2e} "
          f"({len(P)} points), Subdivision Surface {_cube_distance(Q).max():.2e}")
    assert _cube_distance(P).max() <= 1e-6
    assert _cube_distance(Q).max() <= 1e-6
    assert np.abs(P[:8] - base_positions(obj)).max() <= 1e-6
    # without the creases both round the cube off: the check sees it
    obj.data.attributes.remove(obj.data.attributes["crease_edge"])
    obj.data.update()
    assert _cube_distance(evaluated(obj)).max() > 0.05


def test_a_creased_loose_edge_is_ignored_like_the_edge(blender):
    """A stress test (2026-12-07): a wire edge beside the Cube (in no face, so not part of
    the surface; its vertices are unused) creased with the rest (Select All, Shift+E)
    stopped the whole surface with "creases: [(8, 9)] are not edges of the mesh"."""
    from blender_addon import api

    bpy.ops.mesh.primitive_cube_add(size=2.0)
    obj = bpy.context.active_object
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    a, b = bm.verts.new((2.0, 0.0, 0.0)), bm.verts.new((3.0, 0.0, 0.0))
    bm.edges.new((a, b))
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()
    _set_creases(obj.data, "crease_edge", "EDGE", np.ones(len(obj.data.edges)))
    api.add_surface(obj, resolution=6)
    status = api.status(obj)
    assert status["error"] == "" and "unused_vertex" in status["warning"]
    P = evaluated(obj)
    assert len(P) == status["points"] and _cube_distance(P).max() <= 1e-6   # creased cube


def _sphere_loop():
    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8)
    obj = bpy.context.active_object
    dg = bpy.context.evaluated_depsgraph_get()
    me = obj.data.evaluated_get(dg)
    pairs = np.empty(2 * len(me.edges), np.int32)
    me.edges.foreach_get("vertices", pairs)
    z = base_positions(obj)[pairs.reshape(-1, 2), 2]
    zs = np.unique(np.round(base_positions(obj)[:, 2], 6))
    ring = zs[len(zs) // 2 + 1]                       # a latitude above the equator
    loop = np.isclose(z, ring, atol=1e-5).all(axis=1)
    return obj, pairs.reshape(-1, 2), loop


def test_adding_a_crease_updates_the_surface_without_rebuild(blender):
    from blender_addon import api, engine
    from gerbs_core.mesh.surface import BlendingSurface

    obj, pairs, loop = _sphere_loop()
    mod = api.add_surface(obj, resolution=4, rest="bound")   # positions: the linear map
    P0 = evaluated(obj)
    rebuilt = engine.stats["rebuilt"]
    w = np.where(loop, 1.0, 0.0)
    _set_creases(obj.data, "crease_edge", "EDGE", w)
    P1 = evaluated(obj)                                # no Rebuild operator
    assert engine.stats["rebuilt"] == rebuilt + 1
    X = base_positions(obj)
    from blender_addon.mesh_io import faces_from_csr, read_topology
    dg = bpy.context.evaluated_depsgraph_get()
    offsets, corners = read_topology(obj.data.evaluated_get(dg))
    core = BlendingSurface(X, faces_from_csr(offsets, corners),
                           creases=(pairs[loop], np.ones(loop.sum()))).tessellate(4)[0]
    print(f"crease added: moved {np.abs(P1 - P0).max():.3f}, core difference "
          f"{np.abs(P1 - core).max():.1e}")
    assert np.abs(P1 - P0).max() > 1e-3
    assert np.abs(P1 - core).max() <= 1e-5
    # a vertex crease of 1 on the loop: a corner, rebuilt again
    vw = np.zeros(len(obj.data.vertices))
    vw[pairs[loop][0, 0]] = 1.0
    _set_creases(obj.data, "crease_vert", "POINT", vw)
    P2 = evaluated(obj)
    assert engine.stats["rebuilt"] == rebuilt + 2 and np.abs(P2 - P1).max() > 1e-4
    # moving a vertex with the creases unchanged takes the stencil's fast path (the
    # stencil of the creased surface)
    updated = engine.stats["updated"]
    obj.data.vertices[0].co.z += 0.1
    obj.data.update()
    evaluated(obj)
    assert engine.stats["updated"] == updated + 1 and engine.stats["rebuilt"] == rebuilt + 2
    assert api.status(obj, mod)["error"] == ""


def test_creases_set_in_edit_mode_reach_the_surface(blender):
    from blender_addon import api

    obj, pairs, loop = _sphere_loop()
    api.add_surface(obj, resolution=3)
    P0 = evaluated(obj)
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    layer = bm.edges.layers.float.get("crease_edge") or bm.edges.layers.float.new("crease_edge")
    bm.verts.ensure_lookup_table()
    on = {tuple(sorted(p)) for p in pairs[loop].tolist()}
    for e in bm.edges:
        if tuple(sorted(v.index for v in e.verts)) in on:
            e[layer] = 1.0
    bmesh.update_edit_mesh(obj.data)
    P1 = evaluated(obj)
    bpy.ops.object.mode_set(mode="OBJECT")
    assert np.abs(P1 - P0).max() > 1e-3
    assert np.abs(evaluated(obj) - P1).max() <= 1e-6
