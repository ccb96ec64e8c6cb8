"""OBJECT_OT_gerbs_apply: bake the GERBS surface into the object's mesh."""
from __future__ import annotations

import bpy

from .errors import GERBSError

from . import api, ids


class OBJECT_OT_gerbs_apply(bpy.types.Operator):
    """Apply the GERBS Blending Surface modifier (the surface becomes the mesh)"""

    bl_idname = ids.OP_APPLY
    bl_label = "Apply GERBS Surface"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = getattr(context, "active_object", None)
        return obj is not None and api.get_modifier(obj) is not None and obj.mode == "OBJECT"

    def execute(self, context):
        try:
            api.apply(context.active_object)
        except GERBSError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        return {"FINISHED"}
