"""OBJECT_OT_gerbs_select_problem: select the elements the panel's error (else its warning
line) names, in Edit Mode."""
from __future__ import annotations

import bmesh
import bpy

from . import api, engine, ids, problems


def _problems(obj) -> tuple:
    """What the panel names on the base mesh: the error's problem, else the repairs of the
    last build (gerbs_core MeshWarning records); () when there is nothing to select."""
    mod = api.get_modifier(obj) if obj is not None and obj.type == "MESH" else None
    st = engine.get_state(obj, mod) if mod is not None else None
    if st is None or not problems.on_base_mesh(obj, mod):
        return ()
    if st.error:
        return (st.problem,) if st.problem is not None else ()
    return tuple(st.warnings)


def select(obj, items) -> dict:
    """Enter Edit Mode on `obj` and select exactly the elements of `items` (problems or
    warnings); returns the counts selected per kind. Indices outside the mesh are
    skipped."""
    if obj.mode != "EDIT":
        with bpy.context.temp_override(object=obj, active_object=obj, selected_objects=[obj]):
            bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    for seq in (bm.verts, bm.edges, bm.faces):
        seq.ensure_lookup_table()
        for elem in seq:
            elem.select_set(False)
    want = {"vertex": [], "edge": [], "face": []}
    for item in items:
        for kind, elements in problems.selection(item).items():
            want[kind] += elements
    got = {"vertex": 0, "edge": 0, "face": 0}
    for i in want["vertex"]:
        if 0 <= i < len(bm.verts):
            bm.verts[i].select_set(True)
            got["vertex"] += 1
    for a, b in want["edge"]:
        if 0 <= a < len(bm.verts) and 0 <= b < len(bm.verts):
            edge = bm.edges.get((bm.verts[a], bm.verts[b]))
            if edge is not None:
                edge.select_set(True)
                got["edge"] += 1
    for i in want["face"]:
        if 0 <= i < len(bm.faces):
            bm.faces[i].select_set(True)
            got["face"] += 1
    kind = "EDGE" if got["edge"] else "FACE" if got["face"] else "VERT"
    bm.select_mode = {kind}
    bm.select_flush_mode()
    scene = bpy.context.scene
    if scene is not None:
        scene.tool_settings.mesh_select_mode = (kind == "VERT", kind == "EDGE", kind == "FACE")
    bmesh.update_edit_mesh(obj.data, loop_triangles=False, destructive=False)
    return got


class OBJECT_OT_gerbs_select_problem(bpy.types.Operator):
    """Select, in Edit Mode, the vertices, edges or faces the GERBS error names (else
    those the mesh repair changed)"""

    bl_idname = ids.OP_SELECT_PROBLEM
    bl_label = "Select the Problem"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if _problems(getattr(context, "active_object", None)):
            return True
        cls.poll_message_set("No GERBS error or mesh repair of the active object names "
                             "vertices, edges or faces")
        return False

    def execute(self, context):
        obj = context.active_object
        got = select(obj, _problems(obj))
        plural = {"vertex": "vertices", "edge": "edges", "face": "faces"}
        words = [f"{n} {kind if n == 1 else plural[kind]}" for kind, n in got.items() if n]
        self.report({"INFO"}, f"Selected {', '.join(words) or 'nothing'}")
        return {"FINISHED"}
