"""Edit Mode updates: a selection change costs no sync work, a position edit goes through
the stencil's partial update and gives the surface a fresh build gives, also through a
modifier after GERBS."""
import bmesh
import bpy
import numpy as np
import pytest

from .helpers import base_positions, evaluated, make_object, topology

pytestmark = pytest.mark.blender

R = 2


class _Counter:
    """Counts the calls of a function of the add-on (it still runs)."""

    def __init__(self, monkeypatch, module, name):
        self.calls = 0
        inner = getattr(module, name)

        def counted(*args, **kwargs):
            self.calls += 1
            return inner(*args, **kwargs)

        monkeypatch.setattr(module, name, counted)


def _edit(kind="icosphere", rest="bound", after=None):
    from blender_addon import api

    obj = make_object(kind)
    mod = api.add_surface(obj, resolution=R, rest=rest)
    if after is not None:
        extra = obj.modifiers.new("after", after)
        extra.show_in_editmode = True
        if after == "DISPLACE":
            extra.direction, extra.strength = "Z", 0.3  # no texture: every point up 0.15
    X = base_positions(obj)
    P0 = evaluated(obj)
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    return obj, mod, bm, X, P0


def _update(obj):
    bmesh.update_edit_mesh(obj.data, loop_triangles=False, destructive=False)
    return evaluated(obj)


def _statuses():
    from blender_addon import engine
    return dict(engine.stats)


def _reads():
    """How often the sync read everything of the input, or only its positions."""
    from blender_addon import stack
    return {k: stack.reads[k] for k in ("full", "positions")}


def _more(before, after):
    return {k: after[k] - before[k] for k in before}


def _record_positions(mod):
    """The positions the result's record holds (the add-on's own mesh: safe to read)."""
    from blender_addon import geometry_nodes as gn
    from blender_addon import ids

    mesh = gn.get_result(mod).data
    buf = np.empty((len(mesh.vertices), 3), dtype=np.float32)
    mesh.attributes[ids.SNAP_POSITION].data.foreach_get("vector", buf.ravel())
    return buf


def _bm_mesh(bm):
    """(positions (V, 3) float32, faces) of the edit mesh, read from the BMesh."""
    X = np.array([v.co[:] for v in bm.verts], dtype=np.float32)
    return X, [[v.index for v in f.verts] for f in bm.faces]


def test_selection_changes_do_no_sync_work(blender, monkeypatch):
    from blender_addon import geometry_nodes as gn
    from blender_addon import ids, snapshot

    obj, mod, bm, X, P0 = _edit()
    reads = _Counter(monkeypatch, snapshot, "read_snapshot")
    before, inputs = _statuses(), _reads()
    # what the select operators do (ID_RECALC_SELECT: a shading-only update): no sync
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.select_all(action="DESELECT")
    assert np.array_equal(evaluated(obj), P0)
    assert _statuses() == before
    # a script's selection change tags the geometry: one sync, "unchanged", and the
    # result's record is not read back (the state wrote it: the stamp says so)
    bm.verts[5].select_set(True)
    assert np.array_equal(_update(obj), P0)
    after = _statuses()
    assert after.get("unchanged", 0) == before.get("unchanged", 0) + 1
    assert {k: v for k, v in after.items() if k != "unchanged"} == \
        {k: v for k, v in before.items() if k != "unchanged"}
    assert reads.calls == 0
    assert _reads() == inputs  # nothing of the mesh was read either
    # control: a record the state did not write (as after an undo) is read back
    gn.get_result(mod).data[ids.RECORD_STAMP] = "restored by undo"
    bm.verts[5].select_set(False)
    assert np.array_equal(_update(obj), P0)
    assert reads.calls == 1
    bpy.ops.object.mode_set(mode="OBJECT")


def _expected(obj, X_rest, X_new, shift=0.0):
    """The surface a fresh build of the moved mesh bound to the rest shape gives."""
    from gerbs_core import BlendingSurface
    from blender_addon.mesh_io import faces_from_csr

    offsets, corners = topology(obj.data)
    P = BlendingSurface(X_new, faces_from_csr(offsets, corners),
                        rest_positions=X_rest).tessellate(R)[0]
    return P + np.array([0.0, 0.0, shift])


@pytest.mark.parametrize("after", [None, "DISPLACE", "TRIANGULATE"])
def test_moved_vertices_update_like_a_fresh_build(blender, after):
    """One vertex moved twice in Edit Mode (Rest Shape Bound): partial updates of the
    stencil, no rebuild, and the surface of a fresh build each time; with a deform-only
    modifier after GERBS (Displace: read through the channel) and with one that changes
    the mesh (Triangulate: read from the edit mesh)."""
    from blender_addon import engine

    obj, mod, bm, X, P0 = _edit(after=after)
    shift = 0.15 if after == "DISPLACE" else 0.0
    # an icosphere is all triangles: Triangulate keeps the surface's points as they are
    assert np.abs(P0 - _expected(obj, X, X, shift)).max() <= 1e-5
    rebuilt = _statuses().get("rebuilt", 0)
    X_new = X.copy()
    for step, dz in enumerate((0.2, -0.07)):
        bm.verts[3].co.z += dz
        X_new[3, 2] = bm.verts[3].co.z
        P = _update(obj)
        assert np.abs(P - _expected(obj, X, X_new, shift)).max() <= 1e-5
        st = engine.get_state(obj, mod)
        assert st.partial_updates == step + 1  # only the moved vertex's columns
    assert np.abs(P - P0).max() > 0.05
    assert _statuses().get("rebuilt", 0) == rebuilt
    bpy.ops.object.mode_set(mode="OBJECT")


def test_a_move_reads_only_positions_and_writes_the_fresh_result(blender):
    """A position edit in Edit Mode: the channel says the topology and layers are the
    record's, so only positions are read; the record then holds exactly the new
    positions (written vertex by vertex), and the surface is a fresh build's to float32
    round-off, also when the moved set changes and when the result's record is not the
    one the state wrote (then written whole)."""
    from blender_addon import geometry_nodes as gn
    from blender_addon import ids

    obj, mod, bm, X, P0 = _edit()
    for step, verts in enumerate(([3], [3, 17], [17])):
        if step == 2:  # control: as after an undo, the stamp is not the state's
            gn.get_result(mod).data[ids.RECORD_STAMP] = "restored by undo"
        before = _reads()
        for v in verts:
            bm.verts[v].co.z += 0.05 * (step + 1)
        P = _update(obj)
        assert _more(before, _reads()) == {"full": 0, "positions": 1}
        X_new, _ = _bm_mesh(bm)
        assert np.array_equal(_record_positions(mod)[:len(X_new)], X_new)
        fresh = _expected(obj, X, X_new.astype(np.float64)).astype(np.float32)
        assert np.abs(P - fresh).max() <= 4 * np.spacing(np.float32(np.abs(fresh).max()))
    assert np.abs(P - P0).max() > 0.05
    bpy.ops.object.mode_set(mode="OBJECT")


def test_edits_other_than_positions_are_read_in_full(blender, monkeypatch):
    """What the channel must not call "positions only": an edge rotation (same counts of
    everything, other faces: a rebuild of the new faces; the face sizes come from the
    channel, not from Blender's per-face loop_start) and a UV edit (a carried layer:
    mapped again, no rebuild)."""
    from gerbs_core import BlendingSurface

    from blender_addon import mesh_io

    obj, mod, bm, X, P0 = _edit()
    before, rebuilt = _reads(), _statuses().get("rebuilt", 0)
    per_face, inner = [], mesh_io._get

    def counted(collection, name, *args):
        per_face.append(name)
        return inner(collection, name, *args)

    monkeypatch.setattr(mesh_io, "_get", counted)
    bm.edges.ensure_lookup_table()
    assert bmesh.ops.rotate_edges(bm, edges=[bm.edges[10]], use_ccw=False)["edges"]
    bm.faces.index_update()
    bm.faces.ensure_lookup_table()
    P = _update(obj)
    assert _more(before, _reads()) == {"full": 1, "positions": 0}
    assert "value" in per_face and "loop_start" not in per_face  # read, but not per face
    assert _statuses().get("rebuilt", 0) == rebuilt + 1
    X_new, faces = _bm_mesh(bm)
    assert len(faces) == 80 and len(bm.edges) == 120  # the counts are the icosphere's
    fresh = BlendingSurface(X_new.astype(np.float64), np.array(faces)).tessellate(R)[0]
    assert np.abs(P - fresh).max() <= 1e-5 and np.abs(P - P0).max() > 1e-3
    before, statuses = _reads(), _statuses()
    uv = bm.loops.layers.uv.active
    bm.faces[0].loops[0][uv].uv.x += 0.25
    assert np.array_equal(_update(obj), P)
    assert _more(before, _reads()) == {"full": 1, "positions": 0}
    assert _statuses().get("updated", 0) == statuses.get("updated", 0) + 1
    assert _statuses().get("rebuilt", 0) == rebuilt + 1
    bpy.ops.object.mode_set(mode="OBJECT")


def test_a_stale_face_size_channel_in_the_mesh_is_never_taken_for_the_faces(blender):
    """A mesh that carries the channel's face-size attribute from an old Apply (here:
    wrong sizes with the right total) while the node group passes it on untouched (the
    group found the topology the record's): the sync, reading in full because a new
    layer appeared, takes the faces from the mesh, not from that stale attribute."""
    from blender_addon import geometry_nodes as gn
    from blender_addon import ids

    obj, mod, bm, X, P0 = _edit()
    bpy.ops.object.mode_set(mode="OBJECT")
    stale = np.full(len(obj.data.polygons), 3, dtype=np.int32)
    stale[0], stale[1] = 2, 4                    # same corner count, other faces
    obj.data.attributes.new(ids.CHANNEL_FACE_SIZE, "INT", "FACE").data.foreach_set("value", stale)
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    bm.verts[3].co.z += 0.05
    _update(obj)                                 # the record now names this topology
    before = _reads()
    bm.verts.layers.float.new("new_layer")       # a layer the record lacks: read in full
    bm.verts[3].co.z += 0.05
    P = _update(obj)          # the first evaluation already shows the surface
    assert _more(before, _reads()) == {"full": 1, "positions": 0}
    assert not gn.get_error(mod)
    X_new, faces = _bm_mesh(bm)
    assert all(len(f) == 3 for f in faces)
    fresh = _expected(obj, X, X_new.astype(np.float64))
    assert np.abs(P - fresh).max() <= 1e-5
    bpy.ops.object.mode_set(mode="OBJECT")


def _add_layer(bm):
    bm.verts.layers.float.new("added")


def _remove_layer(bm):
    bm.loops.layers.uv.remove(bm.loops.layers.uv.active)


def _change_uv(bm):
    uv = bm.loops.layers.uv.active
    bm.faces.ensure_lookup_table()
    bm.faces[0].loops[0][uv].uv.x += 0.25


@pytest.mark.parametrize("edit", [_add_layer, _remove_layer, _change_uv])
def test_the_first_evaluation_after_a_full_read_edit_shows_the_edited_surface(blender, edit):
    """A move together with an edit that makes the sync read in full (a layer added or
    removed: the layer names on the modifier change; a UV edited: they do not): the very
    evaluation that synced it shows the surface of the edited mesh, not the input passed on
    (the cage) nor the surface before the edit, with the record of the new layers."""
    from blender_addon import geometry_nodes as gn
    from blender_addon import snapshot

    obj, mod, bm, X, P0 = _edit()
    bm.verts[3].co.z += 0.05
    _update(obj)
    before = _reads()
    edit(bm)
    bm.verts[7].co.z -= 0.1
    P = _update(obj)
    assert _more(before, _reads()) == {"full": 1, "positions": 0}
    X_new, _ = _bm_mesh(bm)
    assert P.shape == P0.shape  # not the cage (the icosphere's 162 vertices at R = 2)
    assert np.abs(P - _expected(obj, X, X_new.astype(np.float64))).max() <= 1e-5
    names = set(bm.verts.layers.float.keys()) | set(bm.loops.layers.uv.keys())
    recorded = snapshot.read_snapshot(gn.get_result(mod).data, gn.get_names(mod))
    assert names <= {layer.name for layer in recorded.carried.layers}
    bpy.ops.object.mode_set(mode="OBJECT")


def test_undo_from_object_mode_back_into_edit_mode_shows_the_surface(blender):
    """Found by a test of the interactive workflow: undo from Object Mode back into Edit
    Mode restored the result's older record, the node group showed the base mesh, and
    every sync said 'unchanged' (the input equalled the state's). A sync that finds the
    base mesh shown with an unchanged input now writes the result again."""
    from blender_addon import api

    from .helpers import fresh_surface, positions, topology, undo_into_edit_mode

    bpy.ops.mesh.primitive_grid_add(x_subdivisions=3, y_subdivisions=3, size=2.0)
    obj = bpy.context.active_object
    name = obj.name
    api.add_surface(obj, resolution=2)
    bpy.ops.ed.undo_push(message="added")
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.ed.undo_push(message="edit")
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    bm.verts[5].co.z += 0.3
    bmesh.update_edit_mesh(obj.data)
    bpy.context.view_layer.update()
    bpy.ops.ed.undo_push(message="moved")
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.ops.ed.undo_push(message="object")
    obj, P = undo_into_edit_mode(name)
    X = positions(obj.data)
    offsets, corners = topology(obj.data)
    assert len(P) > len(X) and np.abs(P - fresh_surface(X, offsets, corners, 2)).max() <= 1e-5
