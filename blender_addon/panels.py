"""UI: the Add Modifier menu entry and a status panel in the modifier tab.

The settings are drawn by Blender itself in the Geometry Nodes modifier panel
(they are the node group's inputs). This panel adds what the modifier panel
cannot show: counts, timings, the last error, and Rebuild/Apply/Remove.
"""
from __future__ import annotations

import bpy

from . import api, ids


def draw_menu_entry(self, context):
    self.layout.operator(ids.OP_ADD, text=ids.MENU_LABEL, icon=ids.MENU_ICON)


class GERBS_PT_status(bpy.types.Panel):
    bl_idname = ids.PANEL_STATUS
    bl_label = "GERBS Blending Surface"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "modifier"

    @classmethod
    def poll(cls, context):
        obj = context.object
        return obj is not None and api.get_modifier(obj) is not None

    def draw(self, context):
        layout = self.layout
        obj = context.object
        info = api.status(obj)
        if info["error"]:
            box = layout.box()
            box.alert = True
            box.label(text=info["error"], icon="ERROR")
        elif "points" in info:
            if info["warning"]:
                layout.label(text=info["warning"], icon="INFO")
            layout.label(text=f"{info['points']} points, {info['triangles']} triangles")
            layout.label(text=f"build {info['build_seconds']:.3f} s, "
                              f"update {info['update_seconds'] * 1000:.1f} ms")
        scene_props = getattr(context.scene, ids.SCENE_PROP, None)
        if scene_props is not None:
            layout.prop(scene_props, "live_update")
        row = layout.row(align=True)
        row.operator(ids.OP_REBUILD, text="Rebuild", icon="FILE_REFRESH")
        row.operator(ids.OP_APPLY, text="Apply", icon="CHECKMARK")
        row.operator(ids.OP_REMOVE, text="Remove", icon="X")


CLASSES = (GERBS_PT_status,)


def _menu():
    return getattr(bpy.types, ids.MENU_PARENT, None)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    menu = _menu()
    if menu is not None:
        menu.append(draw_menu_entry)


def unregister() -> None:
    menu = _menu()
    if menu is not None:
        menu.remove(draw_menu_entry)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
