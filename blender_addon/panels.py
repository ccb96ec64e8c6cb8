"""UI: the Add Modifier menu entry and the GERBS panel in the modifier tab.

The panel is the modifier's face: its settings (the node group's inputs, hidden in
the modifier's own list) grouped like Subdivision Surface's -- Resolution Viewport
and Render first, then the shape, with only the chosen kernel's parameters -- each
with a tooltip saying what it does to the shape; the last error as a short
sentence wrapped to the panel's width, with a button that selects the offending
elements in Edit Mode; plain notes about the modifier stack; counts and timings;
Live Update and Rebuild / Apply / Remove. What it shows is :func:`panel_rows`
(testable without a window).
"""
from __future__ import annotations

import bpy

from . import api, engine, ids, problems
from . import geometry_nodes as gn


def draw_menu_entry(self, context):
    self.layout.operator(ids.OP_ADD, text=ids.MENU_LABEL, icon=ids.MENU_ICON)


_SPECS = {s.key: s for s in ids.SETTINGS}
_LABELS = {"resolution": "Resolution Viewport", "render_resolution": "Render",
           "bfbs_left": "Left", "bfbs_right": "Right"}


def setting_rows(mod) -> list:
    """[(section, key, label)] of the settings the panel shows for `mod`: both
    resolutions, the kernel and only its own parameters, the other shape settings, the
    memory budget."""
    try:
        kernel = gn.read_settings(mod)["kernel"]
    except ValueError:  # a bad value (e.g. from a driver): show every parameter to fix it
        kernel = None
    params = [k for name in ids.KERNEL_PARAMETERS
              if kernel is None or name == kernel for k in ids.KERNEL_PARAMETERS[name]]
    rows = [("Resolution", "resolution"), ("Resolution", "render_resolution"),
            ("Shape", "kernel")] + [("Shape", k) for k in params]
    rows += [("Shape", k) for k in ("boundary", "rest", "use_normals")]
    rows += [("Repair", "merge"), ("Repair", "merge_distance")]
    rows += [("Build", "memory_budget")]
    return [(section, key, _LABELS.get(key, _SPECS[key].name)) for section, key in rows]


def panel_rows(obj, mod, width_px: float = 300.0, scale: float = 1.0) -> dict:
    """What the panel shows: {"error": [lines], "select": bool, "warning": [lines] (what
    the mesh repair changed), "notes": [[lines]], "settings": setting_rows,
    "status": [lines]}."""
    info = api.status(obj, mod)
    st = engine.get_state(obj, mod)
    problem = st.problem if st is not None and st.error else None
    out = {"error": [], "select": False, "warning": [], "notes": [],
           "settings": setting_rows(mod), "status": []}
    if info["error"]:
        text = problems.headline(info["error"], problem)
        if problem is not None and not problems.on_base_mesh(obj, mod):
            text += " It is in the mesh the modifiers above GERBS make; fix it there."
        out["error"] = problems.wrap(text, width_px, scale)
        out["select"] = problem is not None and problems.on_base_mesh(obj, mod) \
            and any(problems.selection(problem).values())  # "no faces" names nothing
    elif info["render_error"]:  # the viewport is fine; final renders show the input
        out["error"] = problems.wrap(f"Final render: {problems.headline(info['render_error'])} "
                                     f"Renders show the mesh without the surface until it "
                                     f"builds.", width_px, scale)
    elif info["stale"]:  # Live Update off and the mesh or a setting edited
        out["warning"] = problems.wrap("The surface is out of date: the base mesh shows. "
                                       "Press Rebuild, or turn Live Update on.", width_px, scale)
    elif info["warning"]:  # what the mesh repair changed
        out["warning"] = problems.wrap(problems.headline(info["warning"]), width_px, scale)
        # a warning naming no element (fairing_skipped, thin_part) has nothing to select
        out["select"] = st is not None and any(w.indices or w.edges for w in st.warnings) \
            and problems.on_base_mesh(obj, mod)
    try:
        settings = gn.read_settings(mod)
    except ValueError:
        settings = {}
    scene = bpy.context.scene
    locked = bool(scene is not None and scene.render.use_lock_interface)
    out["notes"] = [problems.wrap(n, width_px, scale) for n in
                    problems.stack_notes(obj, mod, bpy.app.background, locked, settings)]
    if "points" in info:
        held = " (held)" if info["surface_held"] else ""
        out["status"] = [f"{info['points']} points, {info['faces']} faces",
                         f"build {info['build_seconds']:.3f} s, surface "
                         f"{info['surface_seconds']:.3f} s{held}, "
                         f"update {info['update_seconds'] * 1000:.1f} ms"]
    return out


def _draw_settings(layout, mod, rows) -> None:
    paths = gn.property_paths(mod)
    section = None
    col = layout.column()
    col.use_property_split = True
    col.use_property_decorate = True
    for name, key, label in rows:
        if name != section:
            section = name
            sub = col.column(heading=name, align=True)
        sub.prop(mod, paths[key], text=label)


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
        mod = api.get_modifier(obj)
        width = context.region.width if context.region is not None else 300.0
        rows = panel_rows(obj, mod, width, context.preferences.system.ui_scale)
        if rows["error"]:
            box = layout.box()
            box.alert = True
            for k, line in enumerate(rows["error"]):
                box.label(text=line, icon="ERROR" if k == 0 else "BLANK1")
            if rows["select"]:
                box.operator(ids.OP_SELECT_PROBLEM, text="Select in Edit Mode",
                             icon="RESTRICT_SELECT_OFF")
        if rows["warning"]:
            box = layout.box()
            for k, line in enumerate(rows["warning"]):
                box.label(text=line, icon="INFO" if k == 0 else "BLANK1")
            if rows["select"]:
                box.operator(ids.OP_SELECT_PROBLEM, text="Select in Edit Mode",
                             icon="RESTRICT_SELECT_OFF")
        for note in rows["notes"]:
            box = layout.box()
            for k, line in enumerate(note):
                box.label(text=line, icon="INFO" if k == 0 else "BLANK1")
        _draw_settings(layout, mod, rows["settings"])
        for line in rows["status"]:
            layout.label(text=line)
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
