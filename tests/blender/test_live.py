"""Live update: locality of an edit, W @ X fast path, rebuilds, Edit Mode, undo/redo."""
import bmesh
from mathutils import Vector
import bpy
import numpy as np
import pytest

from .helpers import evaluated, face_rings, make_object, positions, topology

pytestmark = pytest.mark.blender

R = 3


def _sample_rings(obj, r, w):
    """Smallest face ring (about vertex w) among the faces each output sample lies on."""
    from blender_addon.mesh_io import faces_from_csr
    from gerbs_core.mesh.topology import MeshTopology
    from gerbs_core.mesh.lattice import Lattice

    offsets, corners = topology(obj.data)
    lat = Lattice(MeshTopology(faces_from_csr(offsets, corners), len(obj.data.vertices)), r)
    ring = face_rings(offsets, corners, len(obj.data.vertices), w)
    out = np.full(lat.n_points, np.iinfo(np.int64).max)
    np.minimum.at(out, lat.local_sample, ring[lat.local_face])
    return out


@pytest.mark.parametrize("kind,w", [("suzanne", 100), ("icosphere", 7), ("mixed", 12)])
def test_moving_one_vertex_changes_only_its_5_ring(blender, kind, w):
    """Locality (gerbs_core.mesh.stencil): X_w enters the coefficients of the vertices
    within 4 rings of w (data rings 2 + 2 coupling sweeps), and S on a face blends the
    l_u of its corners; together: only faces within the 5-ring of w (ring 1 = faces at
    w, ring k+1 = faces sharing a vertex with ring k) change. The changed samples must
    also be exactly those the core's stencil column says."""
    from blender_addon import api, engine

    obj = make_object(kind)
    mod = api.add_surface(obj, resolution=R, rest="bound")  # the linear map of the positions
    P0 = evaluated(obj)
    W = engine.get_state(obj, mod).stencil.matrix().tocsc()
    obj.data.vertices[w].co.x += 0.05
    obj.data.update()
    P1 = evaluated(obj)
    changed = np.flatnonzero(np.abs(P1 - P0).max(axis=1) > 0)
    rings = _sample_rings(obj, R, w)
    assert len(changed) > 0
    assert rings[changed].max() <= 5
    column = W[:, w]
    depends = set(column.indices.tolist())
    # a weight "moves" its sample only if 0.05 * |w| exceeds the float32 resolution of
    # the evaluated positions (Blender stores positions as float32)
    res = 2.0 * np.spacing(np.float32(np.abs(P0).max()))
    strong = set(column.indices[0.05 * np.abs(column.data) > res].tolist())
    assert set(changed.tolist()) <= depends      # nothing outside the stencil's support moved
    assert strong <= set(changed.tolist())       # everything with a real weight moved
    assert rings[sorted(depends)].max() <= 5


def test_fast_path_reuses_stencil_and_matches_rebuild(blender):
    from blender_addon import api, engine

    obj = make_object("suzanne")
    mod = api.add_surface(obj, resolution=R, rest="bound")
    st = engine.get_state(obj, mod)
    X = positions(obj.data)
    rng = np.random.default_rng(1)
    X2 = (X + 0.02 * rng.standard_normal(X.shape)).astype(np.float32)
    obj.data.attributes["position"].data.foreach_set("vector", X2.ravel())
    obj.data.update()
    P_fast = evaluated(obj)
    assert engine.get_state(obj, mod) is st  # same state object: only the stencil ran
    assert np.array_equal(st.positions, X2.astype(np.float64))
    # the fast path is the surface of the moved mesh bound to the REST shape of the build
    from gerbs_core import BlendingSurface
    from blender_addon.mesh_io import faces_from_csr
    offsets, corners = topology(obj.data)
    want = BlendingSurface(X2.astype(np.float64), faces_from_csr(offsets, corners),
                           rest_positions=X.astype(np.float64)).tessellate(R)[0]
    assert np.abs(P_fast - want).max() <= 1e-6


def test_a_layer_added_with_a_move_shows_the_surface_at_once(blender):
    """Object Mode, Rest Shape Bound: an attribute added and a vertex moved in one update
    (the stencil's update with new layer names on the modifier): the evaluation that synced
    it shows the moved surface, not the base mesh passed on."""
    from gerbs_core import BlendingSurface
    from blender_addon import api
    from blender_addon.mesh_io import faces_from_csr

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=R, rest="bound")
    P0, X = evaluated(obj), positions(obj.data)
    obj.data.attributes.new("added", "FLOAT", "POINT")
    obj.data.vertices[3].co.z += 0.05
    obj.data.update()
    P, X2 = evaluated(obj), positions(obj.data)
    assert P.shape == P0.shape
    offsets, corners = topology(obj.data)
    want = BlendingSurface(X2, faces_from_csr(offsets, corners), rest_positions=X).tessellate(R)[0]
    assert np.abs(P - want).max() <= 1e-5 and np.abs(P - P0).max() > 1e-3


def test_topology_change_rebuilds(blender):
    from blender_addon import api

    obj = make_object("grid")
    api.add_surface(obj, resolution=2)
    n0 = len(evaluated(obj))
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=1, use_grid_fill=True)
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()
    n1 = len(evaluated(obj))
    assert n1 > n0
    X = positions(obj.data)
    assert np.abs(evaluated(obj)[: len(X)] - X).max() <= 1e-6


def test_edit_mode_edits_update_live(blender):
    from blender_addon import api

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=2)
    P0 = evaluated(obj)
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    bm.verts[3].co.z += 0.2
    target = bm.verts[3].co.copy()
    bmesh.update_edit_mesh(obj.data)
    P1 = evaluated(obj)
    assert np.abs(P1[3] - np.array(target)).max() <= 1e-6  # still interpolates the moved vertex
    assert np.abs(P1 - P0).max() > 0.05
    # topology edit in Edit Mode: delete a face -> rebuild with a boundary
    bm.faces.ensure_lookup_table()
    bmesh.ops.delete(bm, geom=[bm.faces[0]], context="FACES_ONLY")
    bmesh.update_edit_mesh(obj.data)
    P2 = evaluated(obj)
    assert len(P2) == len(P1)  # samples of the deleted face interior: none at r=2
    bpy.ops.object.mode_set(mode="OBJECT")
    assert len(obj.data.polygons) == 79
    assert np.abs(evaluated(obj) - P2).max() == 0.0


def test_undo_redo_resync(blender):
    """Undo works headless once undo_steps > 0 and steps are pushed (ed.undo_push)."""
    from blender_addon import api

    obj = make_object("icosphere")
    name = obj.name
    api.add_surface(obj, resolution=2)
    P0 = evaluated(obj)
    bpy.ops.ed.undo_push(message="surface added")
    obj.data.vertices[5].co.z += 0.3
    obj.data.update()
    P1 = evaluated(obj)
    bpy.ops.ed.undo_push(message="vertex moved")
    assert np.abs(P1 - P0).max() > 0.05
    assert bpy.ops.ed.undo() == {"FINISHED"}
    obj = bpy.data.objects[name]  # undo re-creates the Python wrappers
    assert np.abs(evaluated(obj) - P0).max() <= 1e-7
    assert bpy.ops.ed.redo() == {"FINISHED"}
    obj = bpy.data.objects[name]
    assert np.abs(evaluated(obj) - P1).max() <= 1e-7
    # and live update still works after undo/redo
    obj.data.vertices[5].co.z -= 0.3
    obj.data.update()
    assert np.abs(evaluated(obj) - P0).max() <= 1e-6


def test_undo_across_add_and_remove(blender):
    from blender_addon import api

    obj = make_object("grid")
    name = obj.name
    X = positions(obj.data)
    bpy.ops.ed.undo_push(message="start")
    api.add_surface(obj, resolution=2)
    P = evaluated(obj)
    bpy.ops.ed.undo_push(message="added")
    api.remove(obj)
    bpy.ops.ed.undo_push(message="removed")
    assert np.array_equal(evaluated(obj), X)
    bpy.ops.ed.undo()
    obj = bpy.data.objects[name]
    assert np.abs(evaluated(obj) - P).max() <= 1e-7
    bpy.ops.ed.undo()
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 0 and np.array_equal(evaluated(obj), X)


def test_one_edit_one_sync_no_feedback_loop(blender):
    """Writing the result triggers depsgraph updates; they must not re-run the work."""
    from blender_addon import api, engine

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=2, rest="bound")  # one linear update per edit
    evaluated(obj)
    before = dict(engine.stats)
    obj.data.vertices[0].co.x += 0.1
    obj.data.update()
    evaluated(obj)
    for _ in range(3):
        obj.update_tag()  # unrelated updates: compared, nothing written
        evaluated(obj)
    after = engine.stats
    assert after["updated"] - before.get("updated", 0) == 1
    assert after["rebuilt"] - before.get("rebuilt", 0) == 0
    assert after["unchanged"] - before.get("unchanged", 0) >= 3


def test_rest_shape_is_kept_until_rebuild(blender):
    """Rest Shape Bound: the rest shape is bound at build time, edits apply the bound
    stencil, and the Rebuild operator rebinds to the current shape."""
    from blender_addon import api

    obj = make_object("icosphere")
    api.add_surface(obj, resolution=3, rest="bound")
    X = positions(obj.data)
    X2 = X * np.array([1.0, 1.0, 3.0])  # stretch: edge lengths change
    obj.data.attributes["position"].data.foreach_set("vector", X2.astype(np.float32).ravel())
    obj.data.update()
    P_bound = evaluated(obj)
    assert np.abs(P_bound[: len(X)] - X2).max() <= 1e-5
    assert bpy.ops.object.gerbs_rebuild() == {"FINISHED"}
    P_rebound = evaluated(obj)
    assert np.abs(P_rebound[: len(X)] - X2).max() <= 1e-5
    assert np.abs(P_rebound - P_bound).max() > 1e-3  # new rest lengths, new surface


def test_undo_apply_brings_the_modifier_back(blender):
    from blender_addon import api

    obj = make_object("icosphere")
    name = obj.name
    X = positions(obj.data)
    api.add_surface(obj, resolution=2)
    P = evaluated(obj)
    bpy.ops.ed.undo_push(message="added")
    api.apply(obj)
    bpy.ops.ed.undo_push(message="applied")
    assert len(obj.modifiers) == 0 and np.abs(positions(obj.data) - P).max() == 0.0
    bpy.ops.ed.undo()
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 1 and np.array_equal(positions(obj.data), X)
    assert np.abs(evaluated(obj) - P).max() <= 1e-7
    obj.data.vertices[0].co.z += 0.2  # live again on the restored modifier
    obj.data.update()
    assert np.abs(evaluated(obj)[0] - positions(obj.data)[0]).max() <= 1e-6
    bpy.ops.ed.redo()
    obj = bpy.data.objects[name]
    assert len(obj.modifiers) == 0


def test_single_vertex_drags_update_locally_and_match_a_full_product(blender):
    """A drag moves one vertex at a time: only that vertex's contribution is applied
    (Stencil.apply_moved); after many such steps the result equals the full product."""
    from blender_addon import api, engine

    obj = make_object("suzanne")
    mod = api.add_surface(obj, resolution=R, rest="bound")
    rng = np.random.default_rng(7)
    for step in range(20):
        v = int(rng.integers(len(obj.data.vertices)))
        obj.data.vertices[v].co += Vector(rng.normal(size=3) * 0.01)
        obj.data.update()
        P = evaluated(obj)
    st = engine.get_state(obj, mod)
    assert st.partial_updates == 20  # every step took the local path
    X = positions(obj.data)
    assert np.abs(P - st.stencil.apply(X)).max() <= 1e-6
    assert np.abs(P[: len(X)] - X).max() <= 1e-6


def test_custom_normals_setting_builds_hermite_surface_and_stays_live(blender):
    """Use Custom Normals passes the vertex normals as Hermite data: not W @ X, so
    every edit rebuilds (tessellate), and the surface still interpolates."""
    from blender_addon import api, engine

    obj = make_object("icosphere")
    # an ellipsoid: on the round sphere the fitted tangent planes are already normal
    # to the (radial) vertex normals, and the two surfaces would coincide
    X0 = positions(obj.data) * np.array([1.0, 1.6, 0.6])
    obj.data.attributes["position"].data.foreach_set("vector", X0.astype(np.float32).ravel())
    obj.data.update()
    mod = api.add_surface(obj, resolution=3)
    P_plain = evaluated(obj)
    api.set_settings(obj, use_normals=True)
    P_normals = evaluated(obj)
    X = positions(obj.data)
    assert api.status(obj)["error"] == "" and engine.get_state(obj, mod).stencil is None
    assert np.abs(P_normals[: len(X)] - X).max() <= 1e-6
    assert np.abs(P_normals - P_plain).max() > 1e-4
    before = engine.stats["rebuilt"]
    obj.data.vertices[2].co.z += 0.2
    obj.data.update()
    P2 = evaluated(obj)
    assert engine.stats["rebuilt"] == before + 1
    assert np.abs(P2[2] - positions(obj.data)[2]).max() <= 1e-6


def test_follow_is_always_the_surface_of_the_current_mesh(blender):
    """Rest Shape Follow (the default): after an edit the surface equals a fresh build of
    the edited mesh (history does not matter), where Bound keeps the old rest shape."""
    from blender_addon import api
    from blender_addon.mesh_io import faces_from_csr
    from gerbs_core import BlendingSurface

    obj = make_object("suzanne")
    api.add_surface(obj, resolution=R)
    X = positions(obj.data)
    X2 = X * np.array([1.0, 1.4, 0.8])
    obj.data.attributes["position"].data.foreach_set("vector", X2.astype(np.float32).ravel())
    obj.data.update()
    P_follow = evaluated(obj)
    offsets, corners = topology(obj.data)
    F = faces_from_csr(offsets, corners)
    X2 = positions(obj.data)
    fresh = BlendingSurface(X2, F).tessellate(R)[0]
    bound = BlendingSurface(X2, F, rest_positions=X).tessellate(R)[0]
    assert np.abs(P_follow - fresh).max() <= 1e-5
    assert np.abs(fresh - bound).max() > 1e-3     # the two policies differ on this edit


def test_live_update_off_says_so_and_turning_it_on_syncs_the_edits(blender):
    """Found by a test of the interactive workflow: with Live Update off an edited mesh
    showed its base mesh with a warning asking to enable the (enabled) add-on, the panel
    said nothing, and turning Live Update on again left the base mesh until the next edit.
    Now the panel notes it is off, the warning names Live Update, and turning it on tags
    the scene's GERBS objects: the next update shows the surface of the edited mesh."""
    from blender_addon import api, panels

    from .helpers import fresh_surface, warnings

    obj = make_object("grid")
    api.add_surface(obj, resolution=2)
    scene = bpy.context.scene
    scene.gerbs.live_update = False
    obj.data.vertices[5].co.z += 0.3
    obj.data.update()
    X = positions(obj.data)
    assert np.array_equal(evaluated(obj), X)                       # the base mesh
    assert "Live Update" in warnings(obj)[0][1]
    rows = panels.panel_rows(obj, api.get_modifier(obj), 600)
    notes = " ".join(" ".join(n) for n in rows["notes"])
    assert "Live Update is off" in notes
    # and scripts and the panel's warning line say the surface is out of date (a newcomer's
    # walk: status reported the last build's points with no warning)
    assert api.status(obj)["stale"] and api.status(obj)["error"] == ""
    assert "out of date" in " ".join(rows["warning"]) and not rows["select"]
    scene.gerbs.live_update = True
    bpy.context.view_layer.update()
    offsets, corners = topology(obj.data)
    P = evaluated(obj)
    assert len(P) > len(X) and np.abs(P - fresh_surface(X, offsets, corners, 2)).max() <= 1e-5
    rows = panels.panel_rows(obj, api.get_modifier(obj), 600)
    notes = " ".join(" ".join(n) for n in rows["notes"])
    assert "Live Update is off" not in notes
    assert not api.status(obj)["stale"] and rows["warning"] == []
