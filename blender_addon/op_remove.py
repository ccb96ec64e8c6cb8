"""OBJECT_OT_gerbs_remove: remove the GERBS modifier and its hidden result object."""
from __future__ import annotations

import bpy

from . import api, ids, polls


class OBJECT_OT_gerbs_remove(bpy.types.Operator):
    """Remove the GERBS Blending Surface modifier (the base mesh is unchanged)"""

    bl_idname = ids.OP_REMOVE
    bl_label = "Remove GERBS Surface"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return polls.with_surface(cls, context)

    def execute(self, context):
        api.remove(context.active_object)
        return {"FINISHED"}
