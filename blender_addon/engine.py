"""Per-modifier caches and the sync step that keeps a result object up to date.

``sync(obj, mod, depsgraph)`` reads what the modifier receives (see
:func:`read_input`) and compares it and the settings with what was last built:

* same topology and settings -> only the cached stencil applied to the new
  positions (every output coordinate is a fixed linear combination of the vertex
  positions for the rest shape bound at build time, kept until ``force=True``, the
  "Rebuild" operator); when only a few vertices moved (a drag) just their
  contribution is applied (``Stencil.apply_moved``), so the cost is local;
* anything else -> a full rebuild through ``gerbs_core`` and a new result mesh;
* nothing changed -> nothing is written (this is what stops the feedback loop
  of the depsgraph handler: writing the result triggers another update).

Every write stores the input it was built from on the result (mesh_io
snapshot, and the settings on the modifier's "Built" inputs), which is what
the node group checks before showing it.

Invalid input never touches the base mesh: the core raises a
``GERBSValueError`` naming the problem and the indices, the message is put on
the modifier (shown as its error, base mesh passed through) and returned.

State is keyed by ``(object.session_uid, modifier.persistent_uid)`` (renaming a
modifier or an object keeps it) and holds only numpy data, never bpy
references, so undo and file loads cannot leave dangling pointers.
"""
from __future__ import annotations

import logging
import time
from collections import Counter
from dataclasses import dataclass

import bpy
import numpy as np

from . import creases as creases_mod
from . import geometry_nodes as gn
from . import mesh_io, results
from . import settings as settings_mod
from .errors import PREFIX, format_error, format_warnings
from .progress import silent
from .stencil_update import apply_stencil

log = logging.getLogger(__name__)


@dataclass
class SurfaceState:
    """What was last built for one modifier (numpy only)."""

    settings: tuple
    input: mesh_io.MeshInput
    positions: np.ndarray  # (V, 3) float64 of input.positions
    stencil: object = None  # gerbs_core.mesh.stencil.Stencil (P points from V positions)
    rest: np.ndarray | None = None  # (V, 3) the rest shape the stencil is bound to
    triangles: np.ndarray | None = None  # (T, 3) int32 output triangles as written
    points: np.ndarray | None = None  # (P, 3) float64 last output (for partial updates)
    partial_updates: int = 0
    n_points: int = 0
    n_triangles: int = 0
    result_uid: int = -1
    error: str = ""
    build_seconds: float = 0.0
    update_seconds: float = 0.0
    warnings: tuple = ()  # gerbs_core.mesh.repair.MeshWarning of the last build


@dataclass(frozen=True)
class SyncResult:
    status: str  # "unchanged" | "updated" | "rebuilt" | "error"
    message: str = ""
    rebind: bool = False  # a linear preview of a Follow surface: rebuild when edits settle


def dragging(obj) -> bool:
    """An interactive Edit Mode session (a window manager exists, not background): the
    one case where a Follow surface is previewed linearly while the user drags."""
    return obj.mode == "EDIT" and not bpy.app.background


_states: dict[tuple, SurfaceState] = {}
stats: Counter = Counter()  # how often each SyncResult status occurred (tests, panel)


def state_key(obj, mod) -> tuple:
    return (obj.session_uid, getattr(mod, "persistent_uid", mod.name))  # (name before 4.2)


def get_state(obj, mod) -> SurfaceState | None:
    return _states.get(state_key(obj, mod))


def known(obj) -> bool:
    """Has any modifier of `obj` been synced (so it may leave garbage behind)?"""
    uid = obj.session_uid
    return any(key[0] == uid for key in _states)


def clear_caches() -> None:
    """Forget every cache (file load, unregister); results rebuild on demand."""
    _states.clear()
    results.clear()


def prune(alive_keys) -> None:
    """Drop the states of modifiers that no longer exist."""
    for key in [k for k in _states if k not in alive_keys]:
        del _states[key]


def set_error(obj, mod, message: str, warning: str = "") -> None:
    """The modifier's error line and its warning line (what a build repaired)."""
    if gn.set_error(mod, message) | gn.set_warning(mod, "" if message else warning):
        obj.update_tag()  # re-evaluate: the Switch node shows the base mesh or the surface


def _fail(obj, mod, key, st, message, progress) -> SyncResult:
    st.error, st.stencil = message, None
    _states[key] = st
    set_error(obj, mod, message)
    progress(1.0, "error")
    return SyncResult("error", message)


# --- what the modifier receives -------------------------------------------------

def _enabled(mod, edit: bool) -> bool:
    return mod.show_viewport and (not edit or mod.show_in_editmode)


def is_active(obj, mod) -> bool:
    """Is the modifier evaluated at all now (else there is nothing to keep current)?"""
    edit = obj.mode == "EDIT"
    return (mod.show_viewport or mod.show_render) and (not edit or mod.show_in_editmode)


def _final_mesh_is_result(final, res, depsgraph) -> bool:
    """Does the evaluated object show the result (rather than its input)?"""
    if res is None:
        return False
    mesh = res.evaluated_get(depsgraph).data
    if (len(final.vertices), len(final.loops), len(final.polygons)) != \
            (len(mesh.vertices), len(mesh.loops), len(mesh.polygons)):
        return False
    return (np.array_equal(mesh_io.read_positions(final), mesh_io.read_positions(mesh))
            and np.array_equal(mesh_io.read_topology(final)[1], mesh_io.read_topology(mesh)[1]))


def read_input(obj, mod, depsgraph, res, normals: bool):
    """What `mod` receives now, read without touching the user's mesh.

    Returns ``(MeshInput, "")``, ``(None, "")`` when the modifier shows the
    result (so it receives exactly the result's snapshot), or ``(None, message)``.

    If no enabled modifier follows `mod`, the evaluated object's final mesh is
    either the result or, while the result is stale, exactly the modifier's
    input (the node group passes it through), including shape keys, animation
    and modifiers above. Otherwise the evaluated copy of the mesh data-block is
    read, which is only the modifier's input when nothing above it changes the
    mesh. In Edit Mode the final mesh is read through ``to_mesh`` (the
    evaluated object's data is the edit cage there).
    """
    edit = obj.mode == "EDIT"
    mods = list(obj.modifiers)
    after = [m for m in mods[mods.index(mod) + 1:] if _enabled(m, edit)]
    obj_eval = obj.evaluated_get(depsgraph)
    if not after and obj_eval.is_evaluated:
        final = obj_eval.to_mesh() if edit else obj_eval.data
        try:
            if _final_mesh_is_result(final, res, depsgraph):
                return None, ""
            return mesh_io.read_mesh(final, normals), ""
        finally:
            if edit:
                obj_eval.to_mesh_clear()
    before = [m for m in mods[:mods.index(mod)] if _enabled(m, edit)]
    keys = obj.data.shape_keys
    if before or (keys is not None and len(keys.key_blocks) > 1):
        names = ", ".join(m.name for m in after)
        return None, (f"{PREFIX}modifiers after it ({names}) hide what it receives: move it "
                      f"last in the stack to use shape keys or the modifiers above it")
    if edit:
        return mesh_io.read_edit_mesh(obj.data, normals), ""
    return mesh_io.read_mesh(obj.data.evaluated_get(depsgraph), normals), ""


# --- sync -------------------------------------------------------------------------

def sync(obj, mod, depsgraph, *, force: bool = False, progress=None) -> SyncResult:
    """Bring `mod`'s result object up to date with what it receives and its settings.

    `depsgraph`: an evaluated depsgraph containing `obj` (the handler's, or
    ``bpy.context.evaluated_depsgraph_get()``). `progress(fraction, message)` is
    called at a few stages of a rebuild. Raises nothing for bad input: errors
    are returned and shown on the modifier.
    """
    result = _sync(obj, mod, depsgraph, force, progress or silent)
    stats[result.status] += 1
    return result


def _evaluated_modifier(obj, mod, depsgraph):
    """The modifier as evaluated (animated and driven settings are current there)."""
    obj_eval = obj.evaluated_get(depsgraph)
    return (obj_eval.modifiers.get(mod.name) or mod) if obj_eval.is_evaluated else mod


def _alive(key) -> bool:
    return key in _states


def _sync(obj, mod, depsgraph, force, progress) -> SyncResult:
    from .errors import GERBSValueError

    key = state_key(obj, mod)
    st = _states.get(key)
    t0 = time.perf_counter()
    res, new = results.ensure_result(obj, mod, key, _alive)
    blank = SurfaceState(settings=(), input=None, positions=None, result_uid=res.session_uid)
    try:
        settings = gn.read_settings(_evaluated_modifier(obj, mod, depsgraph))
    except GERBSValueError as exc:
        return _fail(obj, mod, key, blank, format_error(exc), progress)
    skey = settings_mod.settings_key(settings)
    inp, problem = read_input(obj, mod, depsgraph, None if new else res, settings["use_normals"])
    if problem:
        return _fail(obj, mod, key, blank, problem, progress)
    if inp is None:  # the result is shown, so it is fresh: its snapshot is the input
        inp = mesh_io.read_snapshot(res.evaluated_get(depsgraph).data)
    # creases (blender_addon/creases.py): in the settings key, so a crease change rebuilds
    crz = creases_mod.read(obj, depsgraph, len(inp.positions)) if inp is not None else \
        creases_mod.NONE
    skey = skey + (("creases", crz.key),)
    _copy_materials(obj.data, res.data)
    same = (not force and st is not None and inp is not None and st.settings == skey
            and st.result_uid == res.session_uid and st.input is not None)
    linear = settings["rest"] == "bound" or dragging(obj)
    if same and st.input.same(inp) and (linear or st.rest is None
                                        or np.array_equal(st.rest, st.positions)):
        return SyncResult("error", st.error) if st.error else SyncResult("unchanged")
    if (same and linear and not st.error and st.stencil is not None
            and st.input.same_topology(inp) and np.array_equal(st.input.materials, inp.materials)
            and len(res.data.vertices) == st.n_points and np.all(np.isfinite(inp.positions))):
        X = inp.positions.astype(np.float64)
        mesh_io.write_snapshot(res.data, inp, positions_only=True)
        mesh_io.write_positions(res.data, apply_stencil(st, X))  # (tags the mesh)
        st.input, st.positions = inp, X
        st.update_seconds = time.perf_counter() - t0
        # Follow: the linear update is a preview; the surface of the current mesh is
        # rebuilt when the drag pauses (handlers.settle) or Edit Mode is left
        return SyncResult("updated", rebind=settings["rest"] == "follow")
    if inp is None:
        return _fail(obj, mod, key, blank, f"{PREFIX}internal error: the result shown "
                     f"carries no record of its input", progress)
    return _rebuild(obj, mod, res, settings, skey, inp, progress, t0, crz)


def _build(settings, inp, progress, crz=creases_mod.NONE):
    """(points (P, 3), triangles (T, 3), stencil or None, lattice or None, surface)."""
    from .core import module, scipy_problem
    from .errors import MissingDependencyError

    if problem := scipy_problem():  # a message in the panel and status bar, not a traceback
        raise MissingDependencyError(problem)
    BlendingSurface = module("mesh.surface").BlendingSurface
    args = settings_mod.core_arguments(settings)
    X = inp.positions.astype(np.float64)
    normals = None if inp.normals is None else inp.normals.astype(np.float64)
    progress(0.05, "building surface")
    surface = BlendingSurface(X, inp.faces(), kernel=args.kernel, normals=normals, **args.surface,
                              **crz.core_arguments())  # creases: blender_addon/creases.py
    if normals is not None:  # Hermite normals: not W @ X (the core refuses a stencil)
        progress(0.35, "evaluating surface")
        P, triangles, _ = surface.tessellate(args.resolution)
        return P, triangles, None, None, surface
    progress(0.35, "building stencil")
    stencil = surface.stencil(args.resolution)
    return stencil.apply(X), stencil.triangles, stencil, stencil.lattice, surface


def _rebuild(obj, mod, res, settings, skey, inp, progress, t0, crz=creases_mod.NONE):
    from .errors import GERBSError

    key = state_key(obj, mod)
    X = inp.positions.astype(np.float64)
    st = SurfaceState(settings=skey, input=inp, positions=X, rest=X, result_uid=res.session_uid)
    try:
        P, triangles, st.stencil, lattice, surface = _build(settings, inp, progress, crz)
    except GERBSError as exc:
        return _fail(obj, mod, key, st, format_error(exc), progress)
    except Exception as exc:  # a defect of the core must not reach Blender raw
        log.exception("GERBS: surface build failed for %s", obj.name)
        return _fail(obj, mod, key, st, format_error(exc), progress)
    progress(0.8, "writing result mesh")
    if not np.all(np.isfinite(P)):
        bad = np.flatnonzero(~np.all(np.isfinite(P), axis=1))
        return _fail(obj, mod, key, st, (
            f"{PREFIX}internal error: the surface is not finite at {len(bad)} output points "
            f"(first {bad[:5].tolist()}); base mesh left as is"), progress)
    if len(P) < len(X) or len(triangles) < len(inp.offsets) - 1:  # the snapshot must fit
        return _fail(obj, mod, key, st, (
            f"{PREFIX}resolution {settings['resolution']} gives fewer output points or "
            f"triangles than the mesh has vertices or faces (loose or merged ones); raise "
            f"the resolution"), progress)
    st.points, st.triangles = P, np.asarray(triangles, dtype=np.int32)
    st.warnings = surface.warnings
    for warning in st.warnings:
        log.warning("GERBS: %s: %s", obj.name, warning.message)
    _write_result(res.data, st, _states.get(key), lattice, surface, settings, inp)
    gn.write_built(mod, settings)
    st.n_points, st.n_triangles = len(P), len(st.triangles)
    st.build_seconds = time.perf_counter() - t0
    _states[key] = st
    set_error(obj, mod, "", format_warnings(st.warnings))
    obj.update_tag()
    progress(1.0, "done")
    return SyncResult("rebuilt")


def _write_result(mesh, st, prev, lattice, surface, settings, inp) -> None:
    if (prev is not None and prev.triangles is not None and prev.result_uid == st.result_uid
            and len(mesh.vertices) == len(st.points)
            and np.array_equal(prev.triangles, st.triangles)):
        mesh_io.write_positions(mesh, st.points)  # e.g. a new kernel: same output topology
    else:  # edges from the lattice structure where it has them (no hashing in Blender)
        mesh_io.write_surface(mesh, st.points, st.triangles,
                              edges=lattice.edges() if lattice is not None else None)
    if len(mesh.materials) > 1:  # per-triangle material of the face it tessellates
        lattice = lattice or surface.lattice(settings["resolution"])
        faces = surface.face_map[lattice.triangle_face]  # the input face of each triangle
        mesh_io.write_material_indices(mesh, inp.materials[faces])
    mesh_io.write_snapshot(mesh, inp)


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
        set_error(obj, mod, message)
        out.append(SyncResult("error", message))
    return out
