"""OBJECT_OT_gerbs_add_surface: add the GERBS Blending Surface modifier (menu entry)."""
from __future__ import annotations

import bpy

from . import api, ids, polls
from .progress import Progress
from .properties import settings_annotations, settings_from


class OBJECT_OT_gerbs_add_surface(bpy.types.Operator):
    """Add a GERBS Blending Surface modifier: a C-infinity surface through the mesh vertices"""

    bl_idname = ids.OP_ADD
    bl_label = "GERBS Blending Surface"
    bl_options = {"REGISTER", "UNDO"}
    __annotations__ = settings_annotations()

    @classmethod
    def poll(cls, context):
        return polls.mesh_object(cls, context) is not None

    def execute(self, context):
        obj = context.active_object
        with Progress(window_manager=context.window_manager) as progress:
            settings = settings_from(self)
            if not self.properties.is_property_set("render_resolution"):
                del settings["render_resolution"]  # renders follow the resolution given
            try:  # settings, and that obj has no GERBS modifier yet, are checked by
                # api.add_surface before anything is added
                mod = api.add_surface(obj, progress=progress, raise_errors=False, **settings)
            except (ValueError, api.OperationError) as exc:
                self.report({"ERROR"}, str(exc))
                return {"CANCELLED"}
        status = api.status(obj, mod)
        if status["error"]:
            # modifier kept (fix the mesh and it updates live); base mesh untouched
            self.report({"ERROR"}, status["error"])
            return {"FINISHED"}
        if status["warning"]:
            self.report({"WARNING"}, status["warning"])
        self.report({"INFO"}, f"GERBS surface: {status.get('points', 0)} points, "
                              f"{status.get('build_seconds', 0.0):.2f} s")
        return {"FINISHED"}
