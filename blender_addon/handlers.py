"""Application handlers: live update, undo/redo resync, cache rebuild on load.

``depsgraph_update_post`` collects the GERBS objects whose geometry changed
(mesh edits in Object or Edit Mode, modifier input changes: both tag the
object) and syncs them right in the handler: no ``bpy.ops``, a module-level
guard against re-entrancy, and :func:`engine.sync` writes nothing when nothing
changed. Blender evaluates the depsgraph a second time, without running the
callbacks again, when a post-update callback tagged data (our write into the
result object), so one ``depsgraph.update()`` already shows the new surface.
Background mode has no timers, which is why the work is not deferred to one.

``undo_post`` / ``redo_post`` resync everything (the restored base meshes and
results are compared with the caches); ``load_post`` drops the caches and
rebuilds. Every handler is ``@persistent`` (survives file loads) and removed
on unregister.
"""
from __future__ import annotations

import traceback

import bpy
from bpy.app.handlers import persistent

from . import engine, ids
from .progress import Progress
from . import geometry_nodes as gn

_busy = False  # re-entrancy guard: our own writes trigger depsgraph updates


def _window_manager():
    """The UI's window manager for progress; None in background mode."""
    return None if bpy.app.background else bpy.context.window_manager


status_message = None  # what _status_text last put in the status bar (None: the default)


def _status_text(message) -> None:
    """Show an error in the status bar; None restores the default.

    Also in background mode (a window manager and workspace exist there too, the
    text is simply not drawn), so scripts and tests see the same state as the UI
    through ``status_message``.
    """
    global status_message
    status_message = message
    workspace = getattr(bpy.context, "workspace", None)
    if workspace is not None:
        try:
            workspace.status_text_set(message)
        except (AttributeError, RuntimeError, TypeError):  # no window (e.g. -b --factory-startup)
            pass


_shown: tuple = ()  # errors last shown (console, status bar): shown once, not per update


def _show_errors(errors) -> None:
    global _shown
    if tuple(errors) != _shown:
        for message in errors:
            if message not in _shown:
                print(message)
        _status_text(errors[0] if errors else None)
        _shown = tuple(errors)


def _live(scene) -> bool:
    props = getattr(scene, ids.SCENE_PROP, None) if scene is not None else None
    return props is None or props.live_update


def _sync_objects(objects, force=False) -> None:
    global _busy
    if _busy:
        return
    _busy = True
    try:
        errors = []
        for obj in objects:
            try:
                with Progress(window_manager=_window_manager()) as progress:
                    results = engine.sync_object(obj, force=force, progress=progress)
                errors += [f"{obj.name}: {r.message}" for r in results if r.status == "error"]
            except Exception:  # a handler must never raise into Blender
                traceback.print_exc()
                for mod in gn.gerbs_modifiers(obj):
                    engine._set_error(obj, mod, "GERBS: internal error (see console)")
        _show_errors(errors)
        engine.collect_garbage()
    finally:
        _busy = False


def _changed_objects(depsgraph):
    changed, meshes, groups = [], set(), False
    for update in depsgraph.updates:
        idb = update.id.original
        if isinstance(idb, bpy.types.Object):
            if idb.type == "MESH" and not idb.get(ids.RESULT_TAG) and gn.gerbs_modifiers(idb):
                changed.append(idb)
        elif isinstance(idb, bpy.types.Mesh):
            meshes.add(idb.name)
        elif isinstance(idb, bpy.types.GeometryNodeTree) and gn.is_gerbs_group(idb):
            groups = True
    if meshes or groups:
        seen = {o.name for o in changed}
        for obj in engine.gerbs_objects():
            if obj.name not in seen and (groups or obj.data.name in meshes):
                changed.append(obj)
    return changed


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    if _busy or not _live(scene):
        return
    objects = _changed_objects(depsgraph)
    if objects:
        _sync_objects(objects)
    elif any(isinstance(u.id, bpy.types.Object) for u in depsgraph.updates):
        # a modifier may have been removed: drop its result object
        _sync_objects([])


@persistent
def on_undo_redo(scene, *args) -> None:
    _sync_objects(engine.gerbs_objects())


def resync_all() -> None:
    """Sync every GERBS object now (after register: edits made while the add-on was
    off are picked up). A no-op while Blender restricts bpy.data (startup)."""
    try:
        objects = engine.gerbs_objects()
    except AttributeError:  # bpy.data is _RestrictData during add-on registration at startup
        return
    _sync_objects(objects)


@persistent
def on_load(*args) -> None:
    engine.clear_caches()
    _sync_objects(engine.gerbs_objects())


_HANDLERS = (
    ("depsgraph_update_post", on_depsgraph_update),
    ("undo_post", on_undo_redo),
    ("redo_post", on_undo_redo),
    ("load_post", on_load),
)


def register() -> None:
    for name, func in _HANDLERS:
        lst = getattr(bpy.app.handlers, name)
        # drop stale copies from an earlier load of this module (script reload)
        for old in [f for f in lst if getattr(f, "__name__", None) == func.__name__
                    and getattr(f, "__module__", None) == func.__module__]:
            lst.remove(old)
        lst.append(func)


def unregister() -> None:
    global _shown
    if _shown:  # our message must not outlive the add-on in the status bar
        _status_text(None)
    _shown = ()
    for name, func in _HANDLERS:
        lst = getattr(bpy.app.handlers, name)
        for old in [f for f in lst if getattr(f, "__name__", None) == func.__name__
                    and getattr(f, "__module__", None) == func.__module__]:
            lst.remove(old)
