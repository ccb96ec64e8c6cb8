"""OBJECT_OT_gerbs_rebuild: rebuild the surface from scratch (rebinds metric rest lengths)."""
from __future__ import annotations

import bpy

from . import api, ids, polls
from .progress import Progress


class OBJECT_OT_gerbs_rebuild(bpy.types.Operator):
    """Rebuild the GERBS surface and its stencil from the current mesh"""

    bl_idname = ids.OP_REBUILD
    bl_label = "Rebuild GERBS Surface"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return polls.with_surface(cls, context)

    def execute(self, context):
        obj = context.active_object
        with Progress(window_manager=context.window_manager) as progress:
            results = api.update(obj, force=True, progress=progress, raise_errors=False)
        if results and results[0].status == "error":
            self.report({"ERROR"}, results[0].message)
            return {"CANCELLED"}
        # a further GERBS modifier is ignored by the sync (its own error line says so)
        ignored = [r.message for r in results[1:] if r.status == "error"]
        warning = "; ".join(w for w in [api.status(obj)["warning"]] + ignored if w)
        if warning:
            self.report({"WARNING"}, warning)
        return {"FINISHED"}
