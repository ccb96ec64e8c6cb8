"""OBJECT_OT_gerbs_apply: bake the GERBS surface into the object's mesh."""
from __future__ import annotations

import bpy

from .errors import GERBSError

from . import api, ids, polls


class OBJECT_OT_gerbs_apply(bpy.types.Operator):
    """Apply the GERBS Blending Surface modifier (the surface becomes the mesh)"""

    bl_idname = ids.OP_APPLY
    bl_label = "Apply GERBS Surface"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return polls.with_surface(cls, context, object_mode=True)

    def execute(self, context):
        try:
            api.apply(context.active_object)
        except GERBSError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        return {"FINISHED"}
