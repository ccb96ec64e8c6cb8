"""The panel in a modeller's words (issue 13, item 4): only the chosen kernel's parameters,
tooltips on the modifier's inputs, an error line that fits, and the select operator."""
import bmesh
import bpy
import numpy as np
import pytest

pytestmark = pytest.mark.blender


def _keys(rows):
    return [key for _, key, _ in rows]


def test_the_panel_shows_only_the_chosen_kernels_parameters(blender):
    from blender_addon import api, ids, panels

    bpy.ops.mesh.primitive_cube_add()
    obj = bpy.context.active_object
    mod = api.add_surface(obj, resolution=2)
    every = {k for params in ids.KERNEL_PARAMETERS.values() for k in params}
    for kernel in ids.KERNELS:
        api.set_settings(obj, kernel=kernel)
        shown = _keys(panels.panel_rows(obj, mod)["settings"])
        assert every & set(shown) == set(ids.KERNEL_PARAMETERS[kernel]), kernel
        assert shown[:3] == ["resolution", "render_resolution", "kernel"]
        assert {"boundary", "rest", "use_normals"} <= set(shown)
    # every setting is drawn by the panel (hidden in the modifier's own list), with a
    # tooltip saying what it does
    items = {i.name: i for i in mod.node_group.interface.items_tree
             if getattr(i, "in_out", None) == "INPUT" and i.name != "Geometry"}
    for spec in ids.SETTINGS:
        assert items[spec.name].hide_in_modifier
        assert items[spec.name].description == spec.description and len(spec.description) > 30


def test_the_memory_budget_tooltip_says_what_the_budget_bounds(blender):
    """As the README says: the budget bounds the output; the construction may use the
    larger of it and gerbs_core's BUILD_MIN_BUDGET (2000 MB). The socket and the property
    keep their name and identifier (only the tooltip changed)."""
    from blender_addon import api, ids
    from gerbs_core.mesh.memory import BUILD_MIN_BUDGET

    (spec,) = [s for s in ids.SETTINGS if s.key == "memory_budget"]
    assert (spec.name, spec.default, spec.scale) == ("Memory Budget (MB)", 2000.0, 1.0e6)
    text = spec.description
    assert "a build may use" not in text
    assert "output" in text and f"larger of this and {BUILD_MIN_BUDGET / 1e6:.0f} MB" in text
    bpy.ops.mesh.primitive_cube_add()
    mod = api.add_surface(bpy.context.active_object, resolution=2)
    (item,) = [i for i in mod.node_group.interface.items_tree if i.name == spec.name]
    assert item.description == text
    prop = bpy.ops.object.gerbs_add_surface.get_rna_type().properties["memory_budget"]
    assert prop.description == text  # the Add operator's redo panel shows the same tooltip


def _nan_vertex(obj, index):
    co = obj.data.vertices[index].co
    co.x = float("nan")
    obj.data.update()


def test_the_error_line_fits_the_panel_and_the_operator_selects_the_problem(blender):
    """An invalid coordinate: the panel's error is a short sentence in lines that fit its
    width; the operator enters Edit Mode with exactly the offending vertex selected."""
    from blender_addon import api, ids, panels, problems

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)
    obj = bpy.context.active_object
    mod = api.add_surface(obj, resolution=2)
    assert not bpy.ops.object.gerbs_select_problem.poll()  # nothing to select
    _nan_vertex(obj, 5)
    api.update(obj, raise_errors=False)
    assert api.status(obj)["error"]
    for width in (180.0, 300.0, 600.0):
        rows = panels.panel_rows(obj, mod, width_px=width)
        limit = max(20, int(width / 7.0) - 4)
        assert rows["error"] and all(len(line) <= limit for line in rows["error"])
        assert rows["select"]
    text = " ".join(panels.panel_rows(obj, mod)["error"])
    assert text.startswith("The mesh has 1 vertex") and "NaN" in text
    assert len(problems.wrap(text, 180.0)) > len(problems.wrap(text, 600.0))
    assert bpy.ops.object.gerbs_select_problem.poll()
    bpy.ops.object.gerbs_select_problem()
    assert obj.mode == "EDIT"
    bm = bmesh.from_edit_mesh(obj.data)
    assert [v.index for v in bm.verts if v.select] == [5]
    assert not any(f.select for f in bm.faces)
    bpy.ops.object.mode_set(mode="OBJECT")
    assert ids.OP_SELECT_PROBLEM == "object.gerbs_select_problem"


def test_a_problem_made_above_gerbs_is_not_selected_on_the_base_mesh(blender):
    """Indices of a mesh a modifier above makes name no elements of the base mesh: the
    panel says where to fix it and offers no selection."""
    from blender_addon import api, panels

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)
    obj = bpy.context.active_object
    obj.modifiers.new("Displace", "DISPLACE").strength = float("nan")
    mod = api.add_surface(obj, resolution=2, raise_errors=False)
    rows = panels.panel_rows(obj, mod)
    assert rows["error"] and not rows["select"]
    assert "modifiers above GERBS" in " ".join(rows["error"])
    assert not bpy.ops.object.gerbs_select_problem.poll()
    assert np.isfinite(np.array([v.co for v in obj.data.vertices])).all()


def test_the_warning_line_selects_what_the_repair_changed(blender):
    """A loose vertex (left out by the repair): the panel's warning line names it, wrapped
    to the panel, and the operator selects exactly that vertex."""
    from blender_addon import api, panels

    from .helpers import link_object

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)
    ico = bpy.context.active_object
    X = np.array([v.co[:] for v in ico.evaluated_get(
        bpy.context.evaluated_depsgraph_get()).data.vertices])
    faces = [[v + (v >= 3) for v in p.vertices] for p in ico.data.polygons]
    bpy.data.objects.remove(ico)
    obj = link_object("loose", np.insert(X, 3, [4.0, 0.0, 0.0], axis=0), faces)
    mod = api.add_surface(obj, resolution=2)
    rows = panels.panel_rows(obj, mod, width_px=220.0)
    assert not rows["error"] and rows["warning"] and rows["select"]
    assert "unused_vertex" in " ".join(rows["warning"])
    assert all(len(line) <= max(20, int(220.0 / 7.0) - 4) for line in rows["warning"])
    bpy.ops.object.gerbs_select_problem()
    bm = bmesh.from_edit_mesh(obj.data)
    assert [v.index for v in bm.verts if v.select] == [3]
    bpy.ops.object.mode_set(mode="OBJECT")


def test_a_thin_part_warns_in_the_panel_with_nothing_to_select(blender):
    """Blender's Cube scaled to a 2 x 2 x 0.2 board and the scale applied: the surface
    bulges to 3.3x the board's thickness (a known limit); the warning line says so and what
    helps, where in the stack (a newcomer's walk: the README said "below GERBS", where a
    Bevel rounds GERBS's output and the board stays at 3.3x), the Select button is not
    offered (the warning names no element), and a Bevel modifier above GERBS (2 segments)
    clears it."""
    from blender_addon import api, panels

    bpy.ops.mesh.primitive_cube_add()
    obj = bpy.context.active_object
    obj.scale = (1.0, 1.0, 0.1)
    bpy.ops.object.transform_apply(scale=True)
    mod = api.add_surface(obj, resolution=4)
    status = api.status(obj)
    assert status["error"] == ""
    assert "3.3x the cage's extent along z" in status["warning"]
    assert "bevelling the edges" in status["warning"]
    assert "Bevel modifier above this one in the stack" in status["warning"]
    rows = panels.panel_rows(obj, mod, width_px=400.0)
    assert rows["warning"] and not rows["select"]
    assert [w.type for w in mod.node_warnings] == ["WARNING"]
    # a Bevel above GERBS: the surface stays near the cage, no warning
    bevel = obj.modifiers.new("Bevel", "BEVEL")
    bevel.segments, bevel.width = 2, 0.05
    bpy.ops.object.modifier_move_to_index(modifier="Bevel", index=0)
    P = np.array([v.co[:] for v in obj.evaluated_get(
        bpy.context.evaluated_depsgraph_get()).data.vertices])
    assert np.ptp(P[:, 2]) < 1.7 * 0.2
    assert api.status(obj)["warning"] == "" and not mod.node_warnings


def test_a_surface_through_itself_warns_and_selects_the_faces(blender):
    """A modelling session (2026-12-07): a cup (a Cylinder, its top inset 0.12 and extruded
    down 1.75) came out with its floor through its bottom and its inner wall through the
    outer one, with no word. The warning line says so, and Select selects those faces."""
    import bmesh

    from blender_addon import api, panels
    from tests.core.test_self_crossing import cup

    V, F = cup()
    mesh = bpy.data.meshes.new("cup")
    mesh.from_pydata(V.tolist(), [], [list(f) for f in F])
    mesh.update()
    obj = bpy.data.objects.new("cup", mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    mod = api.add_surface(obj, resolution=4)
    status = api.status(obj)
    assert status["error"] == "" and "passes through itself" in status["warning"]
    (w,) = [w for w in status["warnings"] if w.tag == "self_crossing"]
    rows = panels.panel_rows(obj, mod, width_px=400.0)
    assert rows["warning"] and rows["select"]
    assert bpy.ops.object.gerbs_select_problem() == {"FINISHED"}
    bm = bmesh.from_edit_mesh(obj.data)
    assert sorted(f.index for f in bm.faces if f.select) == sorted(w.indices)
    bpy.ops.object.mode_set(mode="OBJECT")


@pytest.mark.parametrize("faces, headline", [
    ([(0, 1, 2, 3)], "Every face of the mesh is degenerate"),   # one collinear quad
    ([], "The mesh has no faces."),
])
def test_a_mesh_without_a_face_with_an_area_says_which_and_offers_no_select(blender, faces,
                                                                            headline):
    """Found by a test of the interactive workflow: a mesh whose only face is collinear
    said "The mesh has no faces." and offered Select, which then selected nothing. The
    headline now tells the two apart, and Select is offered only for an error that names
    elements."""
    from blender_addon import api, panels
    from blender_addon.api import GERBSSyncError

    from .helpers import link_object

    obj = link_object("flat", [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0)], faces)
    with pytest.raises(GERBSSyncError, match="empty"):
        api.add_surface(obj, resolution=2)
    rows = panels.panel_rows(obj, api.get_modifier(obj), 600)
    assert " ".join(rows["error"]).startswith(headline) and rows["select"] is False
