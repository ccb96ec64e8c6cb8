"""Scripting API (works headless)::

    import blender_addon; blender_addon.register()
    from blender_addon import api
    mod = api.add_surface(obj, resolution=4, degree=2, kernel="erbs")
    api.update(obj)            # after editing obj.data from a script (optional:
                               # any depsgraph update does it too)
    api.apply(obj)             # bake into obj.data
    api.remove(obj)            # or drop the modifier and its hidden result

Settings (keywords, see ``ids.SETTINGS``): kernel ("erbs", "bfbs", "logistic",
"affine"), alpha, beta, gamma, lam, sigma (ERBS), bfbs_left, bfbs_right,
degree (0..3), resolution (segments per edge), mode ("regular", "metric"),
boundary ("keep", "straighten"), use_normals.

Errors: bad settings raise ``ValueError``; an invalid mesh raises
``gerbs_core.errors.InvalidMeshError`` from :func:`add_surface` and
:func:`update` when ``raise_errors=True`` (the default) — the modifier is kept
and shows the message, the base mesh is untouched.
"""
from __future__ import annotations

import bpy

from . import engine, ids
from . import geometry_nodes as gn


class GERBSSyncError(ValueError):
    """The surface could not be built; the message names the problem and indices."""


def _check_mesh_object(obj) -> None:
    if obj is None or obj.type != "MESH":
        raise ValueError(f"expected a mesh object, got {obj!r}")


def _raise_if_error(results, raise_errors: bool) -> None:
    errors = [r.message for r in results if r.status == "error"]
    if errors and raise_errors:
        raise GERBSSyncError("; ".join(errors))


def get_modifier(obj):
    """The object's (first) GERBS modifier, or None."""
    mods = gn.gerbs_modifiers(obj)
    return mods[0] if mods else None


def add_surface(obj, *, progress=None, raise_errors: bool = True, **settings):
    """Add a GERBS Blending Surface modifier to `obj` (a mesh object) and build it.

    Returns the modifier. Raises ``GERBSSyncError`` (a ValueError) naming the
    problem if the mesh is invalid (the modifier stays, showing the error).
    """
    _check_mesh_object(obj)
    unknown = set(settings) - set(ids.SETTING_KEYS)
    if unknown:
        raise ValueError(f"unknown GERBS settings {sorted(unknown)}; expected {list(ids.SETTING_KEYS)}")
    group = gn.ensure_group()
    mod = obj.modifiers.new(ids.MODIFIER_NAME, "NODES")
    mod.node_group = group
    try:
        gn.write_settings(mod, **{**ids.DEFAULTS, **settings})
    except ValueError:
        obj.modifiers.remove(mod)
        raise
    gn.set_error(mod, "")
    result = engine.sync(obj, mod, force=True, progress=progress)
    obj.update_tag()
    _raise_if_error([result], raise_errors)
    return mod


def set_settings(obj, mod=None, **settings) -> None:
    """Change settings of `obj`'s GERBS modifier; the surface updates on the next sync."""
    mod = mod or get_modifier(obj)
    gn.write_settings(mod, **settings)
    obj.update_tag()


def get_settings(obj, mod=None) -> dict:
    return gn.read_settings(mod or get_modifier(obj))


def update(obj, *, force: bool = False, progress=None, raise_errors: bool = True):
    """Sync every GERBS modifier of `obj` now (force: rebuild and rebind rest lengths)."""
    _check_mesh_object(obj)
    results = engine.sync_object(obj, force=force, progress=progress)
    obj.update_tag()
    _raise_if_error(results, raise_errors)
    return results


def apply(obj, mod=None) -> None:
    """Bake the surface into ``obj.data`` (like Apply in the modifier panel)."""
    _check_mesh_object(obj)
    mod = mod or get_modifier(obj)
    if mod is None:
        raise ValueError(f"{obj.name!r} has no GERBS modifier")
    results = [engine.sync(obj, mod)]
    _raise_if_error(results, True)
    if obj.mode != "OBJECT":
        raise RuntimeError("apply needs Object Mode")
    bpy.context.view_layer.update()
    with bpy.context.temp_override(object=obj, active_object=obj, selected_objects=[obj]):
        bpy.ops.object.modifier_apply(modifier=mod.name)
    engine.collect_garbage()


def remove(obj, mod=None) -> None:
    """Remove the GERBS modifier and its hidden result object; the base mesh is as before."""
    _check_mesh_object(obj)
    mod = mod or get_modifier(obj)
    if mod is None:
        return
    obj.modifiers.remove(mod)
    obj.update_tag()
    engine.collect_garbage()


def status(obj, mod=None) -> dict:
    """Counts, timings and the last error of a modifier (for panels and scripts)."""
    mod = mod or get_modifier(obj)
    st = engine.get_state(obj, mod)
    out = {"error": gn.get_error(mod)}
    if st is not None:
        out.update(points=st.n_points, triangles=st.n_triangles,
                   build_seconds=st.build_seconds, update_seconds=st.update_seconds)
    return out
