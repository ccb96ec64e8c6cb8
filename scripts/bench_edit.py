"""The Edit Mode timings of ``bench_blender.py --edit`` (its docstring says what is
timed): GERBS, the anchors (Subdivision Surface, a do-nothing Geometry Nodes modifier)
and no modifier, side by side round by round. Imports nothing of bench_blender (which
imports :func:`edit_mode` and :func:`evaluated_positions` from here)."""
from __future__ import annotations

import statistics
import time

import numpy as np


def evaluated_positions(bpy, obj):
    """(3 V,) float32 positions of `obj`'s evaluated mesh after a depsgraph update."""
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    mesh = obj.evaluated_get(dg).data
    buf = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", buf)  # the evaluated copy (Edit Mode: the cage)
    return buf


class HandlerClock:
    """Times the add-on's depsgraph handler (what of an update is ours in Python) by
    putting a timing wrapper in its place in ``depsgraph_update_post``; a context
    manager: the handler is put back on leaving, also on an error."""

    def __init__(self, bpy):
        from blender_addon import handlers

        self.total, self.lst, self.inner = 0.0, bpy.app.handlers.depsgraph_update_post, \
            handlers.on_depsgraph_update

        def timed(scene, depsgraph):
            t0 = time.perf_counter()
            self.inner(scene, depsgraph)
            self.total += time.perf_counter() - t0

        self.timed = timed

    def __enter__(self):
        self.lst[self.lst.index(self.inner)] = self.timed
        return self

    def __exit__(self, *exc):
        self.lst[self.lst.index(self.timed)] = self.inner
        return False


def do_nothing_group(bpy):
    """A Geometry Nodes group passing its input on (the anchor of any GN modifier)."""
    group = bpy.data.node_groups.new("bench do-nothing", "GeometryNodeTree")
    group.is_modifier = True
    for in_out in ("OUTPUT", "INPUT"):
        group.interface.new_socket("Geometry", in_out=in_out, socket_type="NodeSocketGeometry")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    group.links.new(gin.outputs[0], gout.inputs[0])
    return group


def edit_mode(bpy, obj, repeats):
    """Edit Mode update costs with GERBS, the anchors and no modifier (module docstring),
    printed. Leaves `obj` in Object Mode without modifiers, the do-nothing group removed
    and the add-on's handler in place, also on an error."""
    from blender_addon import api

    for o in bpy.context.view_layer.objects:
        o.select_set(o == obj)
    bpy.context.view_layer.objects.active = obj
    obj.modifiers.clear()
    group = do_nothing_group(bpy)
    try:
        mods = {"GERBS": api.add_surface(obj, resolution=2, rest="bound"),
                "Subsurf 2": obj.modifiers.new("bench subsurf", "SUBSURF"),
                "do-nothing GN": obj.modifiers.new("bench nodes", "NODES")}
        mods["Subsurf 2"].levels = 2
        mods["do-nothing GN"].node_group = group
        for name, m in mods.items():
            m.show_in_editmode = m.show_viewport = name == "GERBS"
        evaluated_positions(bpy, obj)
        bpy.ops.object.mode_set(mode="EDIT")
        for m in mods.values():  # from now on only "Edit Mode" says which is evaluated
            m.show_viewport = True
        rounds = max(repeats, 7)
        rows = _rounds(bpy, obj, mods, rounds)
    finally:
        if obj.mode == "EDIT":
            bpy.ops.object.mode_set(mode="OBJECT")
        obj.modifiers.clear()
        bpy.data.node_groups.remove(group)
    _report(obj, rows, list(mods) + ["none"], rounds)
    return rows


def _cases(bpy, obj):
    """name -> an edit of the Edit Mode mesh (what a select tool, a script, a drag does)."""
    import bmesh

    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    k = [0]

    def vertex():  # through `bm`: a BMVert is invalid once its BMesh's wrapper is freed
        return bm.verts[len(bm.verts) // 2]

    def select_op():  # what the select tools do (ID_RECALC_SELECT)
        bpy.ops.mesh.select_all(action="TOGGLE")

    def select_script():  # a script's selection change: tags the geometry
        k[0] += 1
        vertex().select_set(k[0] % 2 == 0)
        bmesh.update_edit_mesh(obj.data, loop_triangles=False, destructive=False)

    def move():
        k[0] += 1
        vertex().co.z += 1e-3 * (-1) ** k[0]
        bmesh.update_edit_mesh(obj.data, loop_triangles=False, destructive=False)

    return {"selection (select operator)": select_op, "selection (script)": select_script,
            "one-vertex move": move}


def _rounds(bpy, obj, mods, rounds):
    """(case, config) -> [(edit + update, ours, read) seconds per round], configs the
    modifiers of `mods` and "none", side by side in every round."""
    cases = _cases(bpy, obj)
    configs = list(mods) + ["none"]
    rows = {(name, c): [] for name in cases for c in configs}
    with HandlerClock(bpy) as clock:
        def timed(fn):
            """(edit + depsgraph update, time in our handler, reading the evaluated
            positions)"""
            clock.total = 0.0
            t0 = time.perf_counter()
            fn()
            bpy.context.evaluated_depsgraph_get().update()
            t1 = time.perf_counter()
            mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
            attr = mesh.attributes.get("position")  # none: the edit mesh itself (no modifier)
            if attr is not None:
                attr.data.foreach_get("vector", np.empty(len(mesh.vertices) * 3, np.float32))
            return t1 - t0, clock.total, time.perf_counter() - t1

        for _ in range(rounds):  # rounds: every modifier and none, side by side
            for c in configs:
                for name, m in mods.items():  # off in Edit Mode: Blender does not evaluate it
                    m.show_in_editmode = name == c
                for name, fn in cases.items():
                    timed(fn)  # the first update after a switch: not timed
                    rows[name, c].append(
                        sorted((timed(fn) for _ in range(3)), key=lambda r: r[0])[1])
    return rows


def _report(obj, rows, configs, rounds):
    print(f"Edit Mode, {obj.name} ({len(obj.data.vertices)} vertices), GERBS r=2 rest=bound, "
          f"{rounds} rounds (medians; x: median of the per-round ratio to no modifier;\n"
          f"  the edit and the depsgraph update; ours: of it in the add-on's handler; read: "
          f"the evaluated positions after it)")

    def ratio(name, a, b):  # the median over the rounds of a / b within a round
        return statistics.median(x[0] / y[0] for x, y in zip(rows[name, a], rows[name, b]))

    def ms(name, c, i=0):
        return statistics.median(r[i] for r in rows[name, c]) * 1e3

    for name in dict.fromkeys(name for name, _ in rows):
        line = [f"  {name:<28}"] + [f"{c} {ms(name, c):6.2f} ms" + (
            f" {ratio(name, c, 'none'):5.1f}x" if c != "none" else "") for c in configs]
        line[1] += (f" (ours {ms(name, 'GERBS', 1):4.2f}, read {ms(name, 'GERBS', 2):4.2f};"
                    f" {ratio(name, 'GERBS', 'do-nothing GN'):4.2f}x the do-nothing GN)")
        print(" | ".join(line), flush=True)
