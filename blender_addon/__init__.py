"""GERBS Blending Surface: a Blender add-on / extension (thin glue over gerbs_core).

Register from the repository::

    import bpy, blender_addon
    blender_addon.register()
    from blender_addon import api
    api.add_surface(bpy.context.object, resolution=4)

or install the zip built by ``scripts/build_extension.py`` (Blender 4.2+).
All mathematics is in ``gerbs_core``; see ``geometry_nodes.py`` for why the
modifier is a Geometry Nodes modifier fed by a hidden result object.
"""
from __future__ import annotations

bl_info = {  # legacy add-on metadata (the extension uses blender_manifest.toml)
    "name": "GERBS Blending Surface",
    "author": "GERBS for Blender contributors",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "Properties > Modifiers > Add Modifier > Generate",
    "description": "C-infinity blending surfaces through the vertices of any polygon mesh",
    "category": "Mesh",
}

import atexit
import logging

log = logging.getLogger(__name__)


def _modules():
    from . import handlers, panels, properties
    return properties, panels, handlers


def _operator_classes():
    from .op_add_surface import OBJECT_OT_gerbs_add_surface
    from .op_apply import OBJECT_OT_gerbs_apply
    from .op_rebuild import OBJECT_OT_gerbs_rebuild
    from .op_remove import OBJECT_OT_gerbs_remove
    from .op_select_problem import OBJECT_OT_gerbs_select_problem
    return (OBJECT_OT_gerbs_add_surface, OBJECT_OT_gerbs_apply,
            OBJECT_OT_gerbs_rebuild, OBJECT_OT_gerbs_remove, OBJECT_OT_gerbs_select_problem)


def _clear() -> None:
    """Remove everything this add-on may have registered, found by name.

    Name-based, so it also cleans up after a copy of the package that was
    reloaded (Reload Scripts) or imported under another name (the extension).
    """
    import bpy

    from . import engine, ids
    properties, panels, handlers = _modules()
    handlers.unregister()
    menu = getattr(bpy.types, ids.MENU_PARENT, None)
    if menu is not None:
        for func in list(menu._dyn_ui_initialize()):
            if getattr(func, "__name__", "") == panels.draw_menu_entry.__name__ and \
                    getattr(func, "__module__", "").endswith(".panels"):
                menu.remove(func)
    if hasattr(bpy.types.Scene, ids.SCENE_PROP):
        delattr(bpy.types.Scene, ids.SCENE_PROP)
    for cls in (*_operator_classes(), *panels.CLASSES):
        registered = getattr(bpy.types, cls.__name__, None)  # ours or a stale copy
        if registered is not None:
            bpy.utils.unregister_class(registered)
    names = {cls.__name__ for cls in properties.CLASSES}  # not exposed in bpy.types
    for cls in bpy.types.PropertyGroup.__subclasses__():
        if cls.__name__ in names and cls.is_registered:
            bpy.utils.unregister_class(cls)
    engine.clear_caches()


def _at_exit() -> None:
    """Unregister when Python exits with the add-on registered (the bpy module only:
    see compat.at_exit; the Blender application disables add-ons itself)."""
    unregister()


def _report_limitations() -> None:
    """Say once, in the log, what this Blender cannot do (older Blender, no scipy)."""
    from . import compat
    from .core import scipy_problem

    for text in compat.limitations():
        log.info("GERBS: %s", text)
    if problem := scipy_problem():
        log.warning("GERBS: %s", problem)


def register() -> None:
    """Register classes, the menu entry and the handlers. Idempotent."""
    import bpy

    from . import compat

    _clear()
    properties, panels, handlers = _modules()
    properties.register()
    for cls in _operator_classes():
        bpy.utils.register_class(cls)
    panels.register()
    handlers.register()
    handlers.resync_all()  # catch up with edits made while unregistered
    atexit.unregister(_at_exit)
    if compat.at_exit():
        atexit.register(_at_exit)
    _report_limitations()


def unregister() -> None:
    """Undo register() (a no-op if not registered); objects keep their modifiers
    and show their last surface."""
    atexit.unregister(_at_exit)
    _clear()
