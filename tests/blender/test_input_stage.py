"""Everything a build reads comes from the modifier's input, the stage its positions come
from: normals (Use Custom Normals), carried layers, creases, vertex-group weights, with a
deform modifier below GERBS (the final mesh is the deformed one) or above it.

The reference is an independent object: a copy of the mesh with only the modifiers
above GERBS, evaluated by Blender and read directly (its final mesh is GERBS's input).
"""
import bpy
import numpy as np
import pytest

from .helpers import evaluated, fresh_surface, make_object, positions

pytestmark = pytest.mark.blender

R = 2


def _vertex_normals(mesh) -> np.ndarray:
    buf = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertex_normals.foreach_get("vector", buf)
    return buf.reshape(-1, 3)


def _final(obj):
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    return obj.evaluated_get(dg).data


def _twist(obj, name="Twist"):
    """A Simple Deform twist about z: rotates every vertex (and its normal) by up to
    +-0.75 rad, so normals read after it differ from those before by ~0.5."""
    mod = obj.modifiers.new(name, "SIMPLE_DEFORM")
    mod.deform_method, mod.angle = "TWIST", 1.5
    return mod


def _tilted_normals(obj, tilt=(0.6, 0.0, 0.0)):
    """Custom normals: each vertex's radial direction tilted by `tilt` (not the mesh's own)."""
    X = positions(obj.data)
    n = X / np.linalg.norm(X, axis=1)[:, None] + np.asarray(tilt)
    obj.data.normals_split_custom_set_from_vertices((n / np.linalg.norm(n, axis=1)[:, None]).tolist())
    obj.data.update()


def _object(where, use_normals=True, setup=None):
    """An icosphere with custom normals, GERBS, and a twist below (`where` "after") or
    above ("before") it; `setup(obj)` adds what else the mesh carries (and modifiers
    above GERBS)."""
    from blender_addon import api

    obj = make_object("icosphere")
    _tilted_normals(obj)
    if setup is not None:
        setup(obj)
    if where == "before":
        _twist(obj)
    mod = api.add_surface(obj, resolution=R, use_normals=use_normals)
    if where == "after":
        _twist(obj)
    _final(obj)
    return obj, mod


def _input_stage(obj):
    """The mesh GERBS receives, independently: a copy of the mesh with the modifiers
    above GERBS only (the same parameters), evaluated. (positions, normals, carried)."""
    from blender_addon import attributes, mesh_io, stack

    ref = bpy.data.objects.new("reference", obj.data.copy())
    bpy.context.scene.collection.objects.link(ref)
    for m in obj.modifiers:
        if m.type == "NODES":
            break
        copy = ref.modifiers.new(m.name, m.type)
        for prop in m.bl_rna.properties:
            if not prop.is_readonly and prop.identifier not in ("name", "persistent_uid"):
                setattr(copy, prop.identifier, getattr(m, prop.identifier))
    mesh = _final(ref)
    groups = stack.group_names(obj)
    out = (mesh_io.read_positions(mesh), _vertex_normals(mesh),
           attributes.read_carried(mesh, groups))
    copied = ref.data
    bpy.data.objects.remove(ref)
    bpy.data.meshes.remove(copied)
    return out


def _move_vertex(obj, v, dz):
    obj.data.vertices[v].co.z += dz
    obj.data.update()
    return _final(obj)


def _assert_built_from_input(obj, mod):
    """The state's input is GERBS's input (exactly), and the result (GERBS's output,
    before any modifier below) is the core's surface of those positions and normals."""
    from blender_addon import engine
    from blender_addon import geometry_nodes as gn

    X, N, _ = _input_stage(obj)
    st = engine.get_state(obj, mod)
    assert np.array_equal(st.input.positions, X)
    off = np.abs(st.input.normals - N).max()
    assert off == 0.0, f"normals off by {off:.3f} from GERBS's input"
    want = fresh_surface(X, st.input.offsets, st.input.corners, R, normals=N.astype(np.float64))
    got = positions(gn.get_result(mod).data)
    assert np.abs(got - want).max() <= 1e-5
    return got


@pytest.mark.parametrize("where", ["after", "before"])
def test_custom_normals_come_from_the_modifiers_input(blender, where):
    """A twist below GERBS: the final mesh's normals are twisted, GERBS's input's are
    not (they differ by ~0.5: reading the wrong stage fails). A twist above: the input
    is twisted, positions and normals alike. Two edits: the first (a move and a new
    attribute) reads the whole input, the second (a move) only the positions (the
    channel names the record); both must take the input's normals."""
    from blender_addon import stack

    obj, mod = _object(where)
    for step, v in enumerate((3, 17)):
        reads = stack.reads.copy()
        if step == 0:
            obj.data.attributes.new("heat", "FLOAT", "POINT")
        final = _move_vertex(obj, v, 0.1)
        assert stack.reads - reads == {("full", "positions")[step]: 1}
        _assert_built_from_input(obj, mod)
    if where == "after":  # the stage read matters here
        N = _input_stage(obj)[1]
        assert np.abs(_vertex_normals(final)[: len(N)] - N).max() > 0.1


@pytest.mark.skipif(bpy.app.version < (4, 5, 0), reason="before Blender 4.5 vertex_normals "
                    "ignore custom normals: a custom-normals edit changes no input normal")
@pytest.mark.parametrize("where", ["after", "before", "none"])
def test_editing_only_the_custom_normals_rebuilds(blender, where):
    """Use Custom Normals: a normals edit alone (no position moves) must not leave the
    surface of the old normals shown as fresh."""
    from blender_addon import geometry_nodes as gn

    obj, mod = _object(where)
    before = positions(gn.get_result(mod).data)
    _tilted_normals(obj, tilt=(0.0, -0.5, 0.4))
    _final(obj)
    got = _assert_built_from_input(obj, mod)
    assert np.abs(got - before).max() > 1e-3  # the new normals change the surface


def _carried_setup(obj):
    """A UV map, a float vertex attribute, vertex and edge creases, a vertex group."""
    mesh = obj.data
    V, E = len(mesh.vertices), len(mesh.edges)
    rng = np.random.default_rng(1)
    uv = mesh.uv_layers.new(name="UV")
    uv.data.foreach_set("uv", rng.random(2 * len(mesh.loops)).astype(np.float32))
    mesh.attributes.new("heat", "FLOAT", "POINT").data.foreach_set(
        "value", rng.random(V).astype(np.float32))
    mesh.attributes.new("crease_vert", "FLOAT", "POINT").data.foreach_set(
        "value", (np.arange(V) % 7 == 0).astype(np.float32))
    mesh.attributes.new("crease_edge", "FLOAT", "EDGE").data.foreach_set(
        "value", (np.arange(E) % 11 == 0).astype(np.float32))
    group = obj.vertex_groups.new(name="Group")
    for v in range(0, V, 3):
        group.add([v], float(rng.random()), "REPLACE")
    mesh.update()
    # above GERBS, modifiers changing what it carries: the input's UVs and weights are
    # not the mesh's own (reading the data-block's would fail)
    warp = obj.modifiers.new("UVWarp", "UV_WARP")
    warp.uv_layer, warp.offset = "UV", (0.25, -0.5)
    edit = obj.modifiers.new("WeightEdit", "VERTEX_WEIGHT_EDIT")
    edit.vertex_group, edit.falloff_type = "Group", "SHARP"


@pytest.mark.parametrize("where", ["after", "before"])
@pytest.mark.parametrize("use_normals", [False, True])
def test_carried_layers_come_from_the_modifiers_input(blender, where, use_normals):
    """UVs, attributes, creases and vertex-group weights: what the state carries (and
    the creases it builds with) equals GERBS's input, after a full read and after a
    positions-only one."""
    from blender_addon import engine, stack

    obj, mod = _object(where, use_normals, setup=_carried_setup)
    for step, v in enumerate((3, 17)):
        reads = stack.reads.copy()
        if step == 0:  # a new layer: the whole input is read
            obj.data.attributes.new("extra", "FLOAT", "FACE")
        _move_vertex(obj, v, 0.1)
        assert stack.reads - reads == {("full", "positions")[step]: 1}
        X, _, carried = _input_stage(obj)
        st = engine.get_state(obj, mod)
        assert np.array_equal(st.input.positions, X)
        assert st.input.carried.keys() == carried.keys()
        assert {"UV", "heat", "crease_vert", "crease_edge", "Group"} <= {
            layer.name for layer in carried.layers}
        assert st.input.carried.same(carried)
    # the data-block's own layers are not the input's (the test can tell them apart)
    from blender_addon import attributes
    own = attributes.read_carried(obj.data.evaluated_get(bpy.context.evaluated_depsgraph_get()),
                                  stack.group_names(obj))
    assert not own.same(carried)


@pytest.mark.parametrize("mode", ["OBJECT", "EDIT"])
def test_custom_normals_surface_is_shown_when_read_from_the_mesh_itself(blender, mode):
    """A modifier below that changes the mesh (Triangulate): the input is read from the
    mesh data-block (in Edit Mode a copy of its BMesh), whose normals must be bit for
    bit those the node group's check computes, or the surface would never be shown."""
    import bmesh
    from blender_addon import api
    from blender_addon import geometry_nodes as gn

    obj, mod = _object("none")
    obj.modifiers.new("Triangulate", "TRIANGULATE").show_in_editmode = True
    if mode == "EDIT":
        bpy.ops.object.mode_set(mode="EDIT")
    for v in (3, 17):
        if mode == "EDIT":
            bm = bmesh.from_edit_mesh(obj.data)
            bm.verts.ensure_lookup_table()
            bm.verts[v].co.z += 0.1
            bmesh.update_edit_mesh(obj.data, loop_triangles=False, destructive=False)
            shown = evaluated(obj)
        else:
            _move_vertex(obj, v, 0.1)
            shown = positions(_final(obj))
        assert api.status(obj)["error"] == ""
        result = positions(gn.get_result(mod).data)
        assert shown.shape == result.shape and np.abs(shown - result).max() <= 1e-6
    if mode == "EDIT":
        bpy.ops.object.mode_set(mode="OBJECT")
    _assert_built_from_input(obj, mod)
