"""Application handlers: live update, frame changes, undo/redo, file loads.

``depsgraph_update_post`` and ``frame_change_post`` look at the depsgraph's
updates only: an update of anything but a mesh object whose geometry (or
shading) changed costs one type check; a mesh object is synced when it carries a
GERBS modifier. In Edit Mode a shading-only update is a selection change (the
select operators tag ``ID_RECALC_SELECT``; material and UV edits tag the geometry
too) and is skipped. Frame changes matter because animation, drivers and shape-key
values change what the modifier receives without any edit. The sync runs right
in the handler (no ``bpy.ops``, a module-level guard against re-entrancy, and
:func:`engine.sync` writes nothing when nothing changed): Blender evaluates the
depsgraph a second time, without running the callbacks again, when a
post-update callback tagged data (our write into the result object), so one
``depsgraph.update()`` or ``frame_set`` already shows the new surface.
Background mode has no timers, which is why the work is not deferred to one.
The one timer: a Follow surface dragged in Edit Mode is updated linearly while
the drag goes on and rebuilt from the current mesh once the edits pause for
``SETTLE_SECONDS`` (:func:`settle`; interactive sessions only).

Garbage (results of removed modifiers, meshes of result objects deleted by
hand, the unused node group, the channel attributes Blender's own Apply baked into a
mesh: leftovers.py) is collected when a synced object lost its GERBS
modifier, a result was replaced, or a deletion happened (the update touches the
scene and the number of objects, meshes or node groups changed).

``undo_post`` / ``redo_post`` resync everything (the restored base meshes and
results are compared with the caches); ``load_post`` drops the caches, moves
modifiers of older files to the current node group, and resyncs. Every handler
is ``@persistent`` (survives file loads) and removed on unregister.
"""
from __future__ import annotations

import contextlib
import logging
import time

import bpy
from bpy.app.handlers import persistent

from . import engine, ids, leftovers, linked, mesh_io, results
from . import geometry_nodes as gn
from .errors import PREFIX
from .progress import Progress

log = logging.getLogger(__name__)

_busy = False  # re-entrancy guard: our own writes trigger depsgraph updates
_progress_callback = None  # set by the api around the evaluations it triggers
_outcomes = None  # {state key: sync results} of the handler syncs during sync_now's evaluation
_watch = results.Watch()
_errors: dict[tuple, str] = {}  # state key -> current error message (shown in the status bar)
status_message = None  # what _status_text last put in the status bar (None: the default)
SETTLE_SECONDS = 0.4  # a Follow surface is rebuilt once its Edit Mode drag paused this long
_settling: dict[tuple, tuple] = {}  # state key -> (object name, time of its last preview)
_retrying: set = set()  # names of objects to sync again once the depsgraph is evaluated


def _window_manager():
    """The UI's window manager for progress; None in background mode."""
    return None if bpy.app.background else bpy.context.window_manager


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


def _record(key: tuple, name: str, messages: list) -> None:
    """Remember the object's current errors; log each new one once."""
    text = "; ".join(messages)
    if text and _errors.get(key) != f"{name}: {text}":
        log.error("%s: %s", name, text)
    if text:
        _errors[key] = f"{name}: {text}"
    else:
        _errors.pop(key, None)


def _show_errors() -> None:
    first = next(iter(_errors.values()), None)
    if first != status_message:
        _status_text(first)


def _live(scene) -> bool:
    props = getattr(scene, ids.SCENE_PROP, None) if scene is not None else None
    return props is None or props.live_update


@contextlib.contextmanager
def reporting_to(callback):
    """Syncs done by the handlers inside this block report progress to `callback`."""
    global _progress_callback
    previous, _progress_callback = _progress_callback, callback
    try:
        yield
    finally:
        _progress_callback = previous


def _sync_one(obj, depsgraph, force: bool) -> None:
    mods = gn.gerbs_modifiers(obj)
    if not mods or not engine.is_active(obj, mods[0]):
        return
    key = engine.state_key(obj, mods[0])
    try:
        with Progress(callback=_progress_callback, window_manager=_window_manager()) as progress:
            outcome = engine.sync_object(obj, depsgraph, force=force, progress=progress)
        _record(key, obj.name, [r.message for r in outcome if r.status == "error"])
        if not gn.get_render_error(mods[0]):  # cleared by this sync (settings changed)
            _errors.pop(engine.state_key(obj, mods[0], True), None)
        if _outcomes is not None:
            _outcomes[key] = outcome
        if any(r.rebind for r in outcome):
            _settling[key] = (obj.name, time.monotonic())
            if not bpy.app.timers.is_registered(settle):
                bpy.app.timers.register(settle, first_interval=SETTLE_SECONDS)
        if any(r.retry for r in outcome) and not bpy.app.background:
            _retrying.add(obj.name)
            if not bpy.app.timers.is_registered(retry):
                bpy.app.timers.register(retry, first_interval=0.0)
    except Exception:  # a handler must never raise into Blender
        log.exception("GERBS: sync of %s failed", obj.name)
        message = f"{PREFIX}internal error (see the system console)"
        for mod in mods:
            engine.set_error(obj, mod, message)
        _record(key, obj.name, [message])


def settle():
    """Timer: rebuild the Follow surfaces whose Edit Mode drag paused (the linear preview
    becomes the surface of the current mesh). Returns the next interval, or None (done)."""
    now = time.monotonic()
    for key, (name, seen) in list(_settling.items()):
        if now - seen < SETTLE_SECONDS:
            continue
        del _settling[key]
        obj = bpy.data.objects.get(name)
        mods = gn.gerbs_modifiers(obj) if obj is not None else ()
        if not mods or engine.state_key(obj, mods[0]) != key or _busy:
            continue
        _run([obj], bpy.context.evaluated_depsgraph_get(), False, force=True)
    return SETTLE_SECONDS / 2 if _settling else None


def retry():
    """Timer: sync again the objects whose node group was made to pass its input on (a
    layer the record cannot see appeared); the pass-on evaluation has happened."""
    names = list(_retrying)
    _retrying.clear()
    objects = [bpy.data.objects.get(name) for name in names]
    if not _busy:
        _run([o for o in objects if o is not None], bpy.context.evaluated_depsgraph_get(), False)
    return None


def _collect() -> None:
    results.collect_garbage()
    alive = {engine.state_key(o, m) for o in engine.gerbs_objects() for m in gn.gerbs_modifiers(o)}
    # a synced modifier gone (applied, converted or removed): what an Apply baked of it
    leftovers.remove_channels(engine.gone(alive))
    engine.prune(alive)
    for key in [k for k in _errors if k[:2] not in alive]:  # (render keys with theirs)
        del _errors[key]


def _run(objects, depsgraph, garbage: bool, force: bool = False) -> None:
    global _busy
    if _busy:
        return
    _busy = True
    try:
        for obj in objects:
            _sync_one(obj, depsgraph, force)
        if garbage:
            _collect()
        _show_errors()
    finally:
        _watch.seen()
        _busy = False


def _candidates(depsgraph):
    """(GERBS objects whose geometry changed, whether a synced object lost its modifier)."""
    objects, lost = [], False
    for update in depsgraph.updates:
        idb = update.id
        if not isinstance(idb, bpy.types.Object) or idb.type != "MESH":
            continue
        if not (update.is_updated_geometry or update.is_updated_shading):
            continue
        obj = idb.original
        if not update.is_updated_geometry and mesh_io.editing(obj):
            continue  # Edit Mode selection (ID_RECALC_SELECT): nothing a surface depends on
        if gn.gerbs_modifiers(obj):
            objects.append(obj)
        elif engine.known(obj):  # its GERBS modifier was removed or applied
            lost = True
    return objects, lost


def sync_now(obj, *, force: bool = False, progress=None):
    """Evaluate the depsgraph (the handlers sync pending edits, reporting to
    `progress`), then sync `obj` explicitly (a rebuild if `force`; else usually
    "unchanged"). Returns the sync results of its GERBS modifiers."""
    global _busy, _outcomes
    mods = gn.gerbs_modifiers(obj)
    key = engine.state_key(obj, mods[0]) if mods else None
    _outcomes = {}
    try:
        with reporting_to(progress):
            depsgraph = bpy.context.evaluated_depsgraph_get()
        done = _outcomes.get(key)
    finally:
        _outcomes = None
    if done is not None and any(r.retry for r in done):
        # the handler moved it to the current node group: evaluate that, then sync again
        depsgraph = bpy.context.evaluated_depsgraph_get()
        depsgraph.update()
        done = None
    if done is not None and not force:  # the handler just synced it
        return done
    if _busy:
        return []
    _busy = True
    try:
        outcome = engine.sync_object(obj, depsgraph, force=force, progress=progress)
        if any(r.retry for r in outcome):  # e.g. moved to the current node group
            depsgraph = bpy.context.evaluated_depsgraph_get()
            depsgraph.update()
            outcome = engine.sync_object(obj, depsgraph, force=force, progress=progress)
        if key is not None:
            _record(key, obj.name, [r.message for r in outcome if r.status == "error"])
        _show_errors()
        return outcome
    finally:
        _watch.seen()
        _busy = False


def collect_now() -> None:
    """Collect garbage now (after the api removed or applied a modifier)."""
    _collect()
    _show_errors()
    _watch.seen()


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    """depsgraph_update_post and frame_change_post (both get the evaluated depsgraph).

    Costs O(updates): no object updated -> nothing (an O(1) query); deleted
    data-blocks show as a Scene update, and only then are the data-block counts
    compared (a deletion changes them)."""
    if _busy or not depsgraph.id_type_updated("OBJECT"):
        return
    objects, lost = _candidates(depsgraph)
    if depsgraph.mode == "RENDER":  # a final render: its result only (engine.may_write)
        if objects and _live(scene):
            _render_sync(objects, depsgraph)
        return
    garbage = lost or (depsgraph.id_type_updated("SCENE") and _watch.changed())
    if not _live(scene):
        objects = []
    if objects or garbage:
        _run(objects, depsgraph, garbage)


def _render_sync(objects, depsgraph) -> None:
    """Sync the render results for a render's depsgraph: no status bar, no garbage
    collection (the render may run beside the interface)."""
    global _busy
    _busy = True
    try:
        for obj in objects:
            mods = gn.gerbs_modifiers(obj)
            if not mods:
                continue
            try:
                outcome = engine.sync_object(obj, depsgraph)
            except Exception:  # a handler must never raise into Blender
                log.exception("GERBS: render sync of %s failed", obj.name)
                continue
            # the render's own entry (logged once; shown in the status bar by the next
            # viewport update: the render may run beside the interface)
            _record(engine.state_key(obj, mods[0], True), f"{obj.name} (final render)",
                    [r.message for r in outcome if r.status == "error"])
    finally:
        _busy = False


def _upgrade_all() -> None:
    for obj in engine.gerbs_objects():
        if linked.is_linked(obj):  # read-only: its sync says why it cannot update
            continue
        for mod in gn.gerbs_modifiers(obj):
            if gn.upgrade(mod):
                log.info("GERBS: %s: modifier %r moved to node group version %d",
                         obj.name, mod.name, ids.GROUP_VERSION)


def resync_all(force: bool = False) -> None:
    """Sync every GERBS object now (after register, undo, redo and file loads: edits
    made meanwhile are picked up). A no-op while Blender restricts bpy.data."""
    try:
        _upgrade_all()
        objects = engine.gerbs_objects()
        depsgraph = bpy.context.evaluated_depsgraph_get()
    except AttributeError:  # bpy.data is _RestrictData during add-on registration at startup
        return
    _run(objects, depsgraph, garbage=True, force=force)


@persistent
def on_undo_redo(scene, *args) -> None:
    resync_all()


@persistent
def on_load(*args) -> None:
    engine.clear_caches()
    _errors.clear()
    resync_all()


_HANDLERS = (
    ("depsgraph_update_post", on_depsgraph_update),
    ("frame_change_post", on_depsgraph_update),
    ("undo_post", on_undo_redo),
    ("redo_post", on_undo_redo),
    ("load_post", on_load),
)


def _remove(name, func) -> None:
    lst = getattr(bpy.app.handlers, name)
    # also stale copies from an earlier load of this module (script reload)
    for old in [f for f in lst if getattr(f, "__name__", None) == func.__name__
                and getattr(f, "__module__", None) == func.__module__]:
        lst.remove(old)


def register() -> None:
    for name, func in _HANDLERS:
        _remove(name, func)
        getattr(bpy.app.handlers, name).append(func)


def unregister() -> None:
    _settling.clear()
    _retrying.clear()
    if bpy.app.timers.is_registered(retry):
        bpy.app.timers.unregister(retry)
    if bpy.app.timers.is_registered(settle):
        bpy.app.timers.unregister(settle)
    if status_message is not None:  # our message must not outlive the add-on in the status bar
        _status_text(None)
    _errors.clear()
    for name, func in _HANDLERS:
        _remove(name, func)
