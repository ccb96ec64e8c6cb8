"""Scripting API (works headless)::

    import blender_addon; blender_addon.register()
    from blender_addon import api
    mod = api.add_surface(obj, resolution=4, kernel="erbs")
    api.update(obj)            # after editing obj.data from a script (optional:
                               # any depsgraph update does it too)
    api.apply(obj)             # bake into obj.data
    api.remove(obj)            # or drop the modifier and its hidden result

Settings (keywords, see ``ids.SETTINGS`` and ``settings.validate``): kernel
("erbs", "bfbs", "logistic", "affine"), alpha, beta, gamma, lam, sigma (ERBS),
bfbs_left, bfbs_right, resolution (segments per edge in the viewport, Apply and
exports, 1..64), render_resolution (in final renders), boundary ("keep",
"straighten"), rest ("follow", "bound"), use_normals, merge (weld vertices closer than
merge_distance before building: both are needed, merge_distance alone welds nothing),
merge_distance (object units, 0: coincident vertices only), memory_budget (bytes).

Errors (all ``gerbs_core.errors.GERBSError``):

* a bad setting: ``InvalidParameterError`` (a ValueError) naming it, raised
  when it is set; nothing is changed;
* an invalid mesh: :class:`GERBSSyncError` (a ValueError) from
  :func:`add_surface`, :func:`update` and :func:`apply` when ``raise_errors``
  -- the modifier is kept and shows the message, the base mesh is untouched;
* an object without the modifier (or not a mesh), or a ``mod`` that is not one of the
  object's own GERBS modifiers: :class:`NoModifierError`;
* Apply refused by Blender (Edit Mode, a mesh used by several objects) or below an enabled
  modifier (Blender applies a modifier to the base mesh, not to what those above deliver),
  :func:`add_surface` on an object that already has the modifier (one per object), or
  a change (add, settings, apply, remove) of an object linked from a library (read-only:
  linked.py): :class:`OperationError` (a RuntimeError); nothing is changed.
"""
from __future__ import annotations

import bpy

from . import engine, handlers, ids, linked, stack
from . import geometry_nodes as gn
from . import settings as settings_mod
from .errors import GERBSSyncError, NoModifierError, OperationError, operator_message

__all__ = ["add_surface", "apply", "get_modifier", "get_settings", "remove", "set_settings",
           "status", "update", "GERBSSyncError", "NoModifierError", "OperationError"]


def _mesh_object(obj):
    if not isinstance(obj, bpy.types.Object) or obj.type != "MESH":
        raise NoModifierError(f"expected a mesh object, got {obj!r}")
    return obj


def _modifier(obj, mod=None):
    """`obj`'s GERBS modifier: `mod` when given (it must be one of `obj`'s own GERBS
    modifiers: a script passing another modifier, or another object's, must not get that
    one changed, applied or removed), else the first."""
    _mesh_object(obj)
    if mod is None:
        mod = get_modifier(obj)
        if mod is None:
            raise NoModifierError(f"{obj.name!r} has no {ids.MODIFIER_NAME} modifier")
        return mod
    if not isinstance(mod, bpy.types.Modifier) or mod.id_data != obj \
            or not gn.is_gerbs_modifier(mod):
        what = getattr(mod, "name", None)
        owner = getattr(getattr(mod, "id_data", None), "name", None)
        raise NoModifierError(
            f"{what!r} is not a {ids.MODIFIER_NAME} modifier of {obj.name!r}"
            + (f" (it belongs to {owner!r})" if owner not in (None, obj.name) else "")
            if what is not None else f"expected a modifier of {obj.name!r}, got {mod!r}")
    return mod


def _local(obj, what: str):
    """`obj`, unless it is linked from a library (read-only: linked.py)."""
    if linked.is_linked(obj):
        raise OperationError(linked.refusal(obj, what))
    return obj


def _raise_if_error(outcome, raise_errors: bool) -> None:
    errors = [r.message for r in outcome if r.status == "error"]
    if errors and raise_errors:
        raise GERBSSyncError("; ".join(errors))


def get_modifier(obj):
    """The object's (first) GERBS modifier, or None."""
    mods = gn.gerbs_modifiers(obj)
    return mods[0] if mods else None


def add_surface(obj, *, progress=None, raise_errors: bool = True, **settings):
    """Add a GERBS Blending Surface modifier to `obj` (a mesh object) and build it.

    Returns the modifier. Raises, adding nothing: InvalidParameterError for a bad
    setting (checked first), :class:`OperationError` if `obj` already has a GERBS
    modifier (one per object: change its settings with :func:`set_settings`, or
    :func:`remove` it first). Raises ``GERBSSyncError`` naming the problem if the
    mesh is invalid (the modifier stays, showing the error). Without
    ``render_resolution`` renders use ``resolution``.
    """
    _local(_mesh_object(obj), "add the modifier to")
    if "resolution" in settings and "render_resolution" not in settings:
        settings = {**settings, "render_resolution": settings["resolution"]}
    values = settings_mod.validate({**ids.DEFAULTS, **settings})
    existing = get_modifier(obj)
    if existing is not None:  # a second one would be ignored (engine.sync_object)
        raise OperationError(f"{obj.name!r} already has a {ids.MODIFIER_NAME} modifier "
                             f"({existing.name!r}); one per object: change its settings "
                             f"or remove it first")
    mod = obj.modifiers.new(ids.MODIFIER_NAME, "NODES")
    mod.node_group = gn.ensure_group()
    gn.write_settings(mod, **values)
    gn.set_error(mod, "")
    obj.update_tag()
    _raise_if_error(handlers.sync_now(obj, progress=progress), raise_errors)
    return mod


def set_settings(obj, mod=None, **settings) -> None:
    """Change settings of `obj`'s GERBS modifier (validated first: a bad value
    raises InvalidParameterError and changes nothing); the surface follows on
    the next depsgraph update."""
    mod = _modifier(obj, mod)
    _local(obj, "change the settings of")
    gn.write_settings(mod, **settings)
    obj.update_tag()


def get_settings(obj, mod=None) -> dict:
    return gn.read_settings(_modifier(obj, mod))


def update(obj, *, force: bool = False, progress=None, raise_errors: bool = True):
    """Sync `obj`'s GERBS modifier now (force: rebuild and rebind rest lengths); returns
    one SyncResult per GERBS modifier of `obj`, in stack order; raises GERBSSyncError (with
    ``raise_errors``) for the first one's error (a further one is ignored, as its own error
    line says).

    Tags nothing itself: a sync that writes a result tags what it wrote (the result
    object, the modifier's messages), and one that changes nothing must not tag the object,
    which would make Blender share the mesh's arrays with a fresh evaluated copy again and
    move them on the script's next access (held ``mesh.vertices[i]`` would then point at
    freed memory; tests/blender/test_held_references.py)."""
    _modifier(obj)
    outcome = handlers.sync_now(obj, force=force, progress=progress)
    # the first GERBS modifier's error only (as apply): a further one (copied in the
    # modifier panel) is ignored by the sync and says so on its own line; a stress test
    # found Rebuild failing for the copy while the first one had built
    _raise_if_error(outcome[:1], raise_errors)
    return outcome


def apply(obj, mod=None) -> None:
    """Bake the current surface into ``obj.data`` (like Apply in the modifier panel)."""
    mod = _modifier(obj, mod)
    _local(obj, "apply the modifier of")
    if obj.mode != "OBJECT":
        raise OperationError(f"{obj.name!r}: apply needs Object Mode")
    if obj.data.users > 1:
        raise OperationError(f"{obj.name!r}: its mesh {obj.data.name!r} is used by "
                             f"{obj.data.users} objects; make it single-user first")
    # only the applied modifier's errors matter: a further GERBS modifier (copied in
    # the modifier panel) is ignored by the sync and must not block this one
    outcome = handlers.sync_now(obj)
    _raise_if_error(outcome[gn.gerbs_modifiers(obj).index(mod):][:1], True)
    above = [m.name for m in obj.modifiers[:list(obj.modifiers).index(mod)] if m.show_viewport]
    if above:
        # Blender applies a modifier to the base mesh, without those above it: the node
        # group would then see another input than the surface's and pass it on, and the
        # Apply would silently drop the surface (found by an adversarial test)
        raise OperationError(f"{obj.name!r}: apply the modifier(s) above it first "
                             f"({', '.join(repr(n) for n in above)}): Blender applies a "
                             f"modifier to the base mesh, and the surface is built from what "
                             f"they deliver")
    bpy.context.view_layer.update()  # the result written by the sync is what gets applied
    try:
        with bpy.context.temp_override(object=obj, active_object=obj, selected_objects=[obj]):
            bpy.ops.object.modifier_apply(modifier=mod.name)
    except RuntimeError as exc:
        raise OperationError(f"{obj.name!r}: {operator_message(exc)}") from None
    handlers.collect_now()


def remove(obj, mod=None) -> None:
    """Remove the GERBS modifier (`mod`, one of the object's own, or the first) and its
    hidden result object; the base mesh is as before. A no-op if the object has none and
    no `mod` is given; a `mod` that is not its own GERBS modifier: NoModifierError."""
    _mesh_object(obj)
    if mod is None and get_modifier(obj) is None:
        return
    mod = _modifier(obj, mod)
    _local(obj, "remove the modifier of")
    obj.modifiers.remove(mod)
    obj.update_tag()
    handlers.collect_now()


def status(obj, mod=None) -> dict:
    """Counts, timings, the last error and the warning line of a modifier (for panels and
    scripts); ``warnings``: the repairs of the mesh (gerbs_core MeshWarning records);
    ``render_error``: why the last final render's build failed ("" none; its renders show
    the input meanwhile); ``stale``: True while the viewport shows the base mesh without an
    error (the surface is out of date: Live Update off and the mesh or a setting edited;
    Rebuild makes it); the other counts are then those of the last build. It reads the last
    evaluation: after :func:`update`, which writes the surface without evaluating, it says
    True until the next depsgraph update (``bpy.context.view_layer.update()``).
    ``build_seconds``: the last build of the result (the sync); ``surface_seconds``: what
    constructing its surface took, and ``surface_held``: True when that surface was held
    from an earlier build with the same arguments (a resolution change makes only the
    output: build_seconds is then that, a modelling session read it as the surface's)."""
    mod = _modifier(obj, mod)
    st = engine.get_state(obj, mod)
    error = gn.get_error(mod)
    if not error and st is not None and linked.is_linked(obj):  # not on the linked modifier
        error = st.error
    out = {"error": error, "warning": gn.get_warning(mod),
           "render_error": gn.get_render_error(mod)}
    # out of date: no error, yet the viewport shows the base mesh (Live Update off and the
    # mesh or a setting edited; a newcomer's walk found status reporting the old surface)
    layer = bpy.context.view_layer
    shows = None if layer is None else stack.shows_input(obj, mod, layer.depsgraph)
    out["stale"] = bool(shows) and not error
    if st is not None and not st.error:
        out.update(points=st.n_points, faces=st.n_faces, triangles=st.n_triangles,
                   warnings=st.warnings,
                   build_seconds=st.build_seconds, update_seconds=st.update_seconds,
                   surface_seconds=st.surface_seconds, surface_held=st.surface_held)
    return out
