"""Per-modifier caches and the sync step that keeps the result objects up to date.

``sync(obj, mod, depsgraph)`` reads what the modifier receives (stack.read_input:
positions, topology and everything it carries) and compares it and the settings
with what was last built:

* nothing changed -> nothing is written (this is what stops the feedback loop
  of the depsgraph handler: writing the result triggers another update);
* only what it carries changed (UVs, weights, material indices, a new attribute) ->
  the carried layers are mapped again with the build's maps (transfer.py), the
  surface is not rebuilt;
* same topology and settings, positions moved, with a linear update allowed (Rest
  Shape Bound, or an Edit Mode drag) -> only the cached stencil applied to the new
  positions (every output coordinate is a fixed linear combination of the vertex
  positions for the rest shape bound at build time, kept until ``force=True``, the
  "Rebuild" operator); when only a few vertices moved just their contribution
  (``Stencil.apply_moved``), so the cost is local;
* anything else -> a full rebuild through ``gerbs_core`` and a new result mesh; the
  surface (the model) is reused when its ``BlendingSurface`` arguments are exactly those
  of the surface this modifier's viewport or render state holds (build.make_model: a
  Resolution change, a render at the Render Resolution; never for a Rebuild), so only the
  output at the new resolution is made.

Every write stores the input it was built from on the result (snapshot.py), which
is what the node group checks before showing it, with a new stamp: while the node
group shows a result that still carries the stamp its state wrote, the state's input
is the record and nothing is read back (an update that changes nothing costs a few
look-ups).

Viewport and render: a depsgraph in RENDER mode (a final render's frame change)
syncs the render result at the Render Resolution, from what the modifier receives
in the render. It writes Blender data only where that is safe (background, or
Render > Lock Interface on: a render's handlers run beside the interface);
otherwise, and while its own result is not fresh, a render shows the viewport
surface (node_tree.py). A render build that fails puts its message into the
modifier's Render Error (not its Error: the viewport keeps its surface): final renders
then show the modifier's input, as a failed build does in the viewport, never the
viewport surface in its place; the render handler logs it and the panel and
``api.status`` show it. A render that builds clears it, and so does a viewport sync
once the settings differ from those the render failed with.

Invalid input never touches the base mesh: the core raises a
``GERBSValueError`` naming the problem and the indices (a NaN or infinite carried
value is refused before anything is built: finite.py), the message is put on
the modifier (shown as its error, base mesh passed through) and returned; the
problem's elements are kept for the select operator.

State is keyed by ``(object.session_uid, modifier.persistent_uid)`` (renaming a
modifier or an object keeps it; "render" appended for the render result) and
holds only numpy data, never bpy references, so undo and file loads cannot leave
dangling pointers.
"""
from __future__ import annotations

import logging
import time

import bpy
import numpy as np

from . import creases as creases_mod
from . import geometry_nodes as gn
from . import finite, linked, mesh_io, results, snapshot, stack
from . import rest as rest_mod
from . import settings as settings_mod
from . import build as build_mod
from .build import write_carried, write_geometry
from .errors import PREFIX, format_error, format_warnings
from .progress import silent
from .stencil_update import apply_stencil
from .states import (  # noqa: F401  (engine.SurfaceState, engine.stats, ... for callers)
    SurfaceState, SyncResult, get_state, gone, known, prune, state_key, stats)
from .states import bindings, states as _states

log = logging.getLogger(__name__)


def dragging(obj) -> bool:
    """An interactive Edit Mode session (a window manager exists, not background): the
    one case where a Follow surface is previewed linearly while the user drags."""
    return mesh_io.editing(obj) and not bpy.app.background


def clear_caches() -> None:
    """Forget every cache (file load, unregister); results rebuild on demand."""
    _states.clear()
    bindings.clear()
    results.clear()


def set_error(obj, mod, message: str, warning: str = "") -> None:
    """The modifier's error line and its warning line (what a build repaired); never on a
    linked object (read-only: its state holds the message)."""
    if linked.is_linked(obj):
        return
    if gn.set_error(mod, message) | gn.set_warning(mod, "" if message else warning):
        obj.update_tag()  # re-evaluate: the Switch node shows the base mesh or the surface


def set_render_error(obj, mod, message: str) -> None:
    """The modifier's Render Error: while set, final renders show its input."""
    if not linked.is_linked(obj) and gn.set_render_error(mod, message):
        obj.update_tag()  # re-evaluate: the render's Switch shows the input or the surface


def _fail(obj, mod, key, st, message, progress, problem=None, render=False) -> SyncResult:
    st.error, st.stencil, st.problem, st.stamp = message, None, problem, ""
    _states[key] = st
    if render:  # a render's own line: the Error input would hide the viewport surface too
        set_render_error(obj, mod, message)
    else:
        set_error(obj, mod, message)
    progress(1.0, "error")
    return SyncResult("error", message)


def _clear_stale_render_error(obj, mod, settings, crz) -> None:
    """A viewport sync: drop the Render Error of a final render built with other settings
    than the current ones (or in an earlier session): the next render decides anew (it
    shows the input until then only if it cannot build: no Lock Interface)."""
    if not gn.get_render_error(mod):
        return
    failed = _states.get(state_key(obj, mod, True))
    want = _build_key(settings, settings["render_resolution"]) + (("creases", crz.key),)
    if failed is None or (failed.settings and failed.settings != want):
        set_render_error(obj, mod, "")


def is_active(obj, mod) -> bool:
    """Is the modifier evaluated at all now (else there is nothing to keep current)?"""
    edit = mesh_io.editing(obj)
    return (mod.show_viewport or mod.show_render) and (not edit or mod.show_in_editmode)


def may_write(depsgraph) -> bool:
    """May a sync for `depsgraph` write Blender data? Not from a render that runs beside
    the interface (its handlers run in the render thread)."""
    if depsgraph.mode != "RENDER" or bpy.app.background:
        return True
    return bool(depsgraph.scene.render.use_lock_interface)


# --- sync -------------------------------------------------------------------------

def sync(obj, mod, depsgraph, *, force: bool = False, progress=None) -> SyncResult:
    """Bring `mod`'s result object up to date with what it receives and its settings
    (the render result for a RENDER depsgraph).

    `depsgraph`: an evaluated depsgraph containing `obj` (the handler's, or
    ``bpy.context.evaluated_depsgraph_get()``). `progress(fraction, message)` is
    called at a few stages of a rebuild. Raises nothing for bad input: errors
    are returned and shown on the modifier.
    """
    if not may_write(depsgraph):
        return SyncResult("unchanged")
    if not gn.is_current_group(mod.node_group):
        # written like the layer names a handler sync sets (a post-evaluation write, then
        # a tag); this depsgraph shows the old group: sync again once it is evaluated
        message = gn.upgrade_on_sync(obj, mod)
        if message:
            return SyncResult("error", message)
        obj.update_tag()
        return SyncResult("unchanged", retry=True)
    if linked.is_linked(obj):  # library data: read-only (linked.py)
        result = _sync_linked(obj, mod, depsgraph)
    else:
        result = _sync(obj, mod, depsgraph, force, progress or silent)
    stats[result.status] += 1
    return result


def _sync_linked(obj, mod, depsgraph) -> SyncResult:
    """A linked object: nothing is built or written; the state says why the base mesh
    shows (api.status), if it does."""
    from .errors import GERBSValueError

    key = state_key(obj, mod, depsgraph.mode == "RENDER")
    try:
        settings = gn.read_settings(_evaluated_modifier(obj, mod, depsgraph))
        message = linked.check(obj, mod, depsgraph, settings["use_normals"])
    except GERBSValueError as exc:
        message = format_error(exc)
    if not message:
        _states.pop(key, None)
        return SyncResult("unchanged")
    _states[key] = SurfaceState(settings=(), input=None, positions=None, error=message)
    return SyncResult("error", message)


def _evaluated_modifier(obj, mod, depsgraph):
    """The modifier as evaluated (animated and driven settings are current there)."""
    obj_eval = obj.evaluated_get(depsgraph)
    return (obj_eval.modifiers.get(mod.name) or mod) if obj_eval.is_evaluated else mod


def _alive(key) -> bool:
    return key in _states


def _build_key(settings: dict, resolution: int) -> tuple:
    """What a build depends on (one of the two resolutions: the one it is for)."""
    rest = {k: v for k, v in settings.items() if k not in ("resolution", "render_resolution")}
    return settings_mod.settings_key({**rest, "resolution": resolution})


def _counts(mesh) -> tuple:
    return len(mesh.vertices), len(mesh.polygons), len(mesh.loops)


def _fresh_input(obj, mod, depsgraph, res, shown, st, render, settings):
    """The input while the node group shows a result: that result's record (`st`'s input
    while the record carries the stamp `st` wrote: nothing to read). `shown`: the result
    the evaluation showed (another modifier's, for a duplicate's first sync; else `res`).
    None when a render shows the viewport surface and may keep it (same resolution)."""
    shown = shown or res
    if render:
        final = obj.evaluated_get(depsgraph).data
        if _counts(final) != _counts(shown.evaluated_get(depsgraph).data):  # shows the viewport's
            if settings["render_resolution"] == settings["resolution"]:
                return None
            shown = gn.get_result(mod) or res
    if (shown is res and st is not None and st.stamp and not st.error
            and st.result_uid == res.session_uid and snapshot.stamp_of(res.data) == st.stamp):
        return st.input
    return snapshot.read_snapshot(shown.evaluated_get(depsgraph).data, gn.get_names(mod))


def _new_layers(obj, mod, depsgraph, inp, normals):
    """`inp` with the layers the mesh data-block gained since its record (the node group
    cannot see new names). (input, retry): `retry` when they can only be read from
    what the stack delivers, so the node group has been made to pass it on."""
    names = {layer.name for layer in inp.carried.layers}
    if stack.base_names(obj, depsgraph) <= names:
        return inp, False
    st = stack.stack_of(obj, mod, depsgraph.mode == "RENDER")
    if not st.above:  # the data-block's attributes are what the modifier receives
        return inp.with_carried(stack.read_base(obj, depsgraph, normals, carried_only=True)), False
    if gn.set_names(mod, ""):  # no layer fits: every result is stale until the next sync
        obj.update_tag()
    return inp, True


def _sync(obj, mod, depsgraph, force, progress) -> SyncResult:
    from .errors import GERBSValueError

    render = depsgraph.mode == "RENDER"
    key = state_key(obj, mod, render)
    st = _states.get(key)
    t0 = time.perf_counter()
    res, shown = results.ensure_result(obj, mod, key, _alive, render)
    blank = SurfaceState(settings=(), input=None, positions=None, result_uid=res.session_uid)
    try:
        settings = gn.read_settings(_evaluated_modifier(obj, mod, depsgraph))
    except GERBSValueError as exc:
        return _fail(obj, mod, key, blank, format_error(exc), progress, render=render)
    if not render and settings["render_resolution"] != settings["resolution"]:
        results.ensure_result(obj, mod, state_key(obj, mod, True), _alive, render=True)
    resolution = settings["render_resolution" if render else "resolution"]
    skey = _build_key(settings, resolution)
    view = _states.get(state_key(obj, mod))
    known_input = (st or view).input if (st or view) is not None else None
    # the channel names the viewport result's record (its stamp says which write)
    record = (view.input, view.stamp) if view is not None else None
    # stale: the node group passed its input on (read from the channel): the base mesh shows
    inp, problem, stale = stack.read_input(obj, mod, depsgraph, settings["use_normals"],
                                           known_input, record)
    if problem:
        return _fail(obj, mod, key, blank, problem, progress, render=render)
    retry = False
    if inp is stack.FRESH:
        inp = _fresh_input(obj, mod, depsgraph, res, shown, st, render, settings)
        if inp is None and render:
            return SyncResult("unchanged")
        if inp is not None:
            inp, retry = _new_layers(obj, mod, depsgraph, inp, settings["use_normals"])
    elif inp is None:
        return SyncResult("unchanged")  # not evaluated in this depsgraph
    if inp is None:
        return _fail(obj, mod, key, blank, f"{PREFIX}internal error: the result shown "
                     f"carries no record of its input", progress, render=render)
    # a NaN or infinite carried value would be recorded and never compare equal (finite.py);
    # an input carrying the state's own layers was checked when it was read
    if st is None or st.input is None or inp.carried is not st.input.carried:
        bad = finite.non_finite(inp)
        if bad is not None:
            return _fail(obj, mod, key, blank, format_error(bad), progress, problem=bad,
                         render=render)
    if force and not render:
        _states.pop(state_key(obj, mod, True), None)  # renders rebuild too
    # creases (blender_addon/creases.py) from what the modifier receives: in the settings
    # key, so a crease change rebuilds
    crz = creases_mod.from_carried(inp.carried, inp.offsets, inp.corners)
    skey = skey + (("creases", crz.key),)
    if not render:
        _clear_stale_render_error(obj, mod, settings, crz)
    _copy_materials(obj.data, res.data)
    outcome = _update(obj, mod, res, key, st, settings, skey, inp, resolution, force, t0,
                      stale)
    if outcome is None:
        bound = _rest_shape(obj, mod, res, shown, (st, view), inp, settings, force, render)
        outcome = _rebuild(obj, mod, res, settings, skey, inp, (resolution, crz, bound, force),
                           progress, t0, render)
    return SyncResult(outcome.status, outcome.message, outcome.rebind, retry) if retry else outcome


def _update(obj, mod, res, key, st, settings, skey, inp, resolution, force, t0, stale=False):
    """The cheap outcomes (unchanged, carried layers only, linear positions), or None.
    `stale`: the node group showed the base mesh; an input equal to the state's then means
    the result's record is not the state's (an undo restored an older one: found by a test
    of the interactive workflow, undo from Object Mode back into Edit Mode left the base
    mesh shown, every sync 'unchanged'), and the result is written again (None)."""
    same = (not force and st is not None and st.settings == skey
            and st.result_uid == res.session_uid and st.input is not None)
    if not same:
        return None
    linear = settings["rest"] == "bound" or dragging(obj)
    settled = linear or st.rest is None or np.array_equal(st.rest, st.positions)
    if st.input.same(inp) and settled:
        if st.error:
            return SyncResult("error", st.error)
        return None if stale else SyncResult("unchanged")
    if st.error or st.transfer is None:
        return None
    carried_same = (np.array_equal(st.input.materials, inp.materials)
                    and inp.carried.same(st.input.carried))
    # a record that changes may no longer fit (a layer added at resolution 1): the rebuild
    # says so; an unchanged one fits (a drag's positions: nothing to check on its path)
    if not carried_same and snapshot.misfit(res.data, inp):
        return None
    if st.input.same_geometry(inp) and settled:  # only what it carries changed
        st.stamp = write_carried(res, mod, st.transfer, inp, st.record)
        st.input = inp
        st.update_seconds = time.perf_counter() - t0
        obj.update_tag()
        return SyncResult("updated")
    if (linear and st.stencil is not None and st.input.same_topology(inp)
            and len(res.data.vertices) == st.n_points and np.all(np.isfinite(inp.positions))):
        X = inp.positions.astype(np.float64)
        points, moved = apply_stencil(st, X)
        if points is None:  # beyond float32: a rebuild reports it (not_finite_message)
            return None
        if carried_same:  # the record's positions: only the moved ones while it is st's
            own = snapshot.stamp_of(res.data) == st.stamp
            st.stamp = snapshot.write_positions(res.data, inp, moved if own else None)
        else:
            st.stamp = write_carried(res, mod, st.transfer, inp, st.record)
        mesh_io.write_positions(res.data, points)  # (tags the mesh)
        st.input, st.positions = inp, X
        st.update_seconds = time.perf_counter() - t0
        # Follow: the linear update is a preview; the surface of the current mesh is
        # rebuilt when the drag pauses (handlers.settle) or Edit Mode is left
        return SyncResult("updated", rebind=settings["rest"] == "follow")
    return None


def as_stored(points: np.ndarray) -> np.ndarray:
    """The output points as the result mesh stores them (float32; beyond its range: inf)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return points.astype(np.float32)


def not_finite_message(points: np.ndarray, points32: np.ndarray) -> str:
    """"" when every output point is finite as stored (float32), else the error: a NaN or
    infinity of the core (an internal error), or a finite surface beyond float32's range
    (a mesh of huge coordinates, e.g. scaled to 3e38: its surface overshoots them)."""
    bad = np.flatnonzero(~np.all(np.isfinite(points32), axis=1))
    if not len(bad):
        return ""
    if np.all(np.isfinite(points[bad])):
        why = (f": its coordinates exceed the single precision Blender stores (about "
               f"{float(np.finfo(np.float32).max):.1e}); scale the mesh down")
        return (f"{PREFIX}the surface is not finite at {len(bad)} output points (first "
                f"{bad[:5].tolist()}){why}; base mesh left as is")
    return (f"{PREFIX}internal error: the surface is not finite at {len(bad)} output points "
            f"(first {bad[:5].tolist()}); base mesh left as is")


def _rest_shape(obj, mod, res, shown, states, inp, settings, force, render):
    """The rest shape a build keeps (Rest Shape Bound: rest.py), or None: bind the current
    positions (a Rebuild, Follow, a new topology, none kept)."""
    if force or settings["rest"] != "bound":
        return None
    results = (shown, res) + ((gn.get_result(mod),) if render else ())
    return rest_mod.kept(inp, states, results, bindings.get(state_key(obj, mod), ()))


def _held_models(obj, mod, render: bool, force: bool) -> tuple:
    """The surfaces the modifier's two states hold (this result's first): a build whose
    ``BlendingSurface`` arguments equal one's reuses it (build.make_model). None for a
    Rebuild (`force`), which constructs the surface anew."""
    if force:
        return ()
    held = (_states.get(state_key(obj, mod, r)) for r in (render, not render))
    return tuple(st.model for st in held if st is not None and st.model is not None)


def _rebuild(obj, mod, res, settings, skey, inp, build, progress, t0, render):
    """A full build at ``build = (resolution, creases, rest shape or None, force)`` into
    result `res`: the surface of a held model when its arguments are the same and not
    `force` (only the output at `resolution` is made), else a new one."""
    resolution, crz, bound, force = build
    from .errors import GERBSError, InvalidMeshError

    key = state_key(obj, mod, render)
    X = inp.positions.astype(np.float64)
    st = SurfaceState(settings=skey, input=inp, positions=X, rest=X if bound is None else bound,
                      result_uid=res.session_uid)
    # a Bound surface is given its rest shape even when it binds the current positions
    # (the same surface as rest None), so its later builds have the same arguments
    rest = st.rest if settings["rest"] == "bound" else None
    try:
        progress(0.05, "building surface")
        arguments = build_mod.surface_arguments(settings, inp, crz, rest)
        # kept on the state even if the output fails (a resolution over the memory budget)
        held = _held_models(obj, mod, render, force)
        st.model = build_mod.make_model(arguments, held)
        st.surface_seconds = st.model.seconds
        st.surface_held = any(st.model is m for m in held)
        built = build_mod.evaluate(st.model, arguments, resolution, progress)
    except GERBSError as exc:
        return _fail(obj, mod, key, st, format_error(exc), progress,
                     problem=exc if isinstance(exc, InvalidMeshError) else None, render=render)
    except Exception as exc:  # a defect of the core must not reach Blender raw
        log.exception("GERBS: surface build failed for %s", obj.name)
        st.model = None  # not offered for reuse
        return _fail(obj, mod, key, st, format_error(exc), progress, render=render)
    progress(0.8, "writing result mesh")
    P = built.points
    P32 = as_stored(P)
    message = not_finite_message(P, P32)
    if message:
        return _fail(obj, mod, key, st, message, progress, render=render)
    prev = _states.get(key)
    previous = prev.transfer if prev is not None and prev.result_uid == st.result_uid else None
    st.transfer = write_geometry(res.data, built, previous, inp)
    misfit = snapshot.misfit(res.data, inp)
    if misfit:  # the record of the input (and a rest shape) must fit on the output
        return _fail(obj, mod, key, st, (
            f"{PREFIX}the output at resolution {resolution} has {misfit}; raise the "
            f"resolution"), progress, render=render)
    # checked first (a review: a Bound mesh with loose vertices at resolution 1 failed
    # with a raw ValueError writing its rest shape on fewer output points)
    rest_mod.write(res.data, rest)  # kept with it
    rest_mod.remember(bindings, key[:2], inp, rest)
    st.stencil, st.points, st.warnings = built.stencil, P, built.surface.warnings
    st.points32 = P32  # what write_geometry wrote
    # logged when they change, not at every rebuild (a Follow drag rebuilds at each pause:
    # a test of the interactive workflow saw the same repair logged at every step)
    said = prev.warnings if prev is not None and prev.warnings is not None else ()
    if [w.message for w in st.warnings] != [w.message for w in said]:
        for warning in st.warnings:
            log.warning("GERBS: %s: %s", obj.name, warning.message)
    st.record = gn.settings_record(settings, resolution)
    st.stamp = write_carried(res, mod, st.transfer, inp, st.record)
    st.n_points, st.n_faces = len(P), st.transfer.n_faces
    st.n_triangles = built.lattice.n_triangles
    st.build_seconds = time.perf_counter() - t0
    _states[key] = st
    if render:
        set_render_error(obj, mod, "")
    else:
        set_error(obj, mod, "", format_warnings(st.warnings))
    # no obj.update_tag(): the writes above tagged the result object, whose change
    # re-evaluates this object through the node group's Object Info; a tag of the object
    # would make Blender share its mesh's arrays with a new evaluated copy, and the
    # script's next access would move them (held references: test_held_references.py)
    progress(1.0, "done")
    return SyncResult("rebuilt")


def _copy_materials(base, result) -> None:
    if list(result.materials) != list(base.materials):
        result.materials.clear()
        for mat in base.materials:
            result.materials.append(mat)


def gerbs_objects():
    """Mesh objects carrying at least one GERBS modifier (scans bpy.data)."""
    return [o for o in bpy.data.objects if o.type == "MESH" and gn.gerbs_modifiers(o)]


def sync_object(obj, depsgraph, *, force=False, progress=None) -> list[SyncResult]:
    """Sync the object's GERBS modifier; further GERBS modifiers are refused (each
    would need the output of the one before, which no handler can read)."""
    mods = gn.gerbs_modifiers(obj)
    out = [sync(obj, mods[0], depsgraph, force=force, progress=progress)] if mods else []
    for mod in mods[1:]:
        message = f"{PREFIX}one GERBS Blending Surface modifier per object; this one is ignored"
        if may_write(depsgraph):
            set_error(obj, mod, message)
        out.append(SyncResult("error", message))
    return out
