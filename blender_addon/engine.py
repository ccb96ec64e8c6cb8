"""Per-modifier caches and the sync step that keeps a result object up to date.

``sync(obj, mod)`` compares the base mesh and the modifier's settings with
what was last built for this modifier:

* same topology, settings (and normals use) -> only ``W @ X`` with the cached
  sparse stencil (DESIGN section 5: in both face-shape modes every output
  coordinate is a fixed linear combination of the vertex positions; mode
  ``metric`` keeps the rest edge lengths bound at build time until
  :func:`sync` is called with ``force=True``, the "Rebuild" operator); when
  only a few vertices moved (an Edit Mode drag) just their columns are
  applied, ``P += W[:, moved] dX``, so the cost is local;
* anything else -> a full rebuild through ``gerbs_core`` (surface, stencil,
  triangles) and a new result mesh;
* nothing changed -> nothing is written (this is what stops the feedback loop
  of the depsgraph handler: writing the result triggers another update).

Invalid input never touches the base mesh: the core raises a
``GERBSValueError`` naming the problem and the indices, the message is put on
the modifier (shown as its error, base mesh passed through) and returned.

State is keyed by ``(object.session_uid, modifier.name)`` and holds only numpy
data, never bpy references, so undo and file loads cannot leave dangling
pointers; ``load_post`` drops them and rebuilds (handlers.py).
"""
from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass

import bpy
import numpy as np

from . import geometry_nodes as gn
from . import ids, mesh_io
from .progress import silent


@dataclass
class SurfaceState:
    """What was last built for one modifier (numpy only)."""

    settings: tuple
    offsets: np.ndarray
    corners: np.ndarray
    positions: np.ndarray
    normals: np.ndarray | None = None
    matrix: object = None  # scipy.sparse csr (P, V)
    triangles: np.ndarray | None = None  # (T, 3) int32 output triangles as written
    points: np.ndarray | None = None  # (P, 3) float64 last output (for partial updates)
    matrix_csc: object = None  # W as csc, made on the first partial update
    partial_updates: int = 0
    n_points: int = 0
    n_triangles: int = 0
    result_uid: int = -1
    error: str = ""
    build_seconds: float = 0.0
    update_seconds: float = 0.0


@dataclass(frozen=True)
class SyncResult:
    status: str  # "unchanged" | "updated" | "rebuilt" | "error"
    message: str = ""


_states: dict[tuple, SurfaceState] = {}
stats: Counter = Counter()  # how often each SyncResult status occurred (tests, panel)
_owners: dict[int, tuple] = {}  # result object's session_uid -> owning state key


def state_key(obj, mod) -> tuple:
    return (obj.session_uid, mod.name)


def get_state(obj, mod) -> SurfaceState | None:
    return _states.get(state_key(obj, mod))


def clear_caches() -> None:
    """Forget every cache (file load, unregister); results rebuild on demand."""
    _states.clear()
    _owners.clear()


def make_kernel(settings: dict):
    """The gerbs_core kernel object named by the settings."""
    from gerbs_core.kernels import ERBS, BFBS, Affine, LogisticStep

    name = settings["kernel"]
    if name == "erbs":
        return ERBS(alpha=settings["alpha"], beta=settings["beta"], gamma=settings["gamma"],
                    lam=settings["lam"], sigma=settings["sigma"])
    if name == "bfbs":
        return BFBS(settings["bfbs_left"], settings["bfbs_right"])
    if name == "logistic":
        return LogisticStep()
    if name == "affine":
        return Affine()
    raise ValueError(f"kernel: unknown kernel {name!r}")


def format_error(exc: Exception) -> str:
    """One line naming the problem and where it is (for panels, reports, the console)."""
    from gerbs_core.errors import InvalidMeshError, ResourceLimitError

    if isinstance(exc, InvalidMeshError):
        where = f"{exc.element} indices {list(exc.indices[:10])}" if exc.indices else "the mesh"
        return f"GERBS: invalid mesh ({exc.problem}) at {where}: {exc}"
    if isinstance(exc, ResourceLimitError):
        return f"GERBS: too large: {exc}"
    return f"GERBS: {exc}"


def _result_alive(key: tuple, result_uid: int) -> bool:
    """Does the object/modifier `key` still exist and use the result `result_uid`?"""
    uid, mod_name = key
    for obj in bpy.data.objects:
        if obj.session_uid == uid:
            mod = obj.modifiers.get(mod_name)
            if mod is not None and gn.is_gerbs_modifier(mod):
                res = gn.get_result(mod)
                return res is not None and res.session_uid == result_uid
            return False
    return False


def new_result_object(obj):
    mesh = bpy.data.meshes.new(f"{ids.RESULT_NAME} {obj.name}")
    res = bpy.data.objects.new(mesh.name, mesh)
    res[ids.RESULT_TAG] = True
    return res


def ensure_result(obj, mod):
    """The modifier's hidden result object; a new one if missing or shared with a copy."""
    key = state_key(obj, mod)
    res = gn.get_result(mod)
    if res is not None:
        owner = _owners.get(res.session_uid)
        if res.type != "MESH" or (owner is not None and owner != key
                                  and _result_alive(owner, res.session_uid)):
            res = None  # e.g. the object was duplicated with its modifier
    if res is None:
        res = new_result_object(obj)
        gn.set_result(mod, res)
        # an ID property write does not tag depsgraph relations; re-assigning the
        # group through RNA does, so the new object is evaluated in this update
        mod.node_group = mod.node_group
        _states.pop(key, None)
    _owners[res.session_uid] = key
    return res


def _settings_key(settings: dict) -> tuple:
    return tuple(sorted(settings.items()))


def _set_error(obj, mod, message: str) -> None:
    if gn.set_error(mod, message):
        obj.update_tag()  # re-evaluate: the Switch node shows the base mesh or the surface


def sync(obj, mod, *, force: bool = False, progress=None) -> SyncResult:
    """Bring `mod`'s result object up to date with `obj`'s base mesh and settings.

    `progress(fraction, message)` is called at a few stages of a rebuild.
    Raises nothing for bad input: errors are returned and shown on the modifier.
    """
    result = _sync(obj, mod, force, progress)
    stats[result.status] += 1
    return result


def _sync(obj, mod, force, progress) -> SyncResult:
    progress = progress or silent
    key = state_key(obj, mod)
    mesh = obj.data
    settings = gn.read_settings(mod)
    skey = _settings_key(settings)
    res = ensure_result(obj, mod)
    t0 = time.perf_counter()
    X = mesh_io.read_positions(mesh)
    offsets, corners = mesh_io.read_topology(mesh)
    normals = mesh_io.read_vertex_normals(mesh) if settings["use_normals"] else None
    st = _states.get(key)
    same = (not force and st is not None and st.settings == skey
            and st.result_uid == res.session_uid
            and np.array_equal(st.offsets, offsets) and np.array_equal(st.corners, corners))
    if same and st.error:
        if np.array_equal(st.positions, X):
            return SyncResult("error", st.error)
    elif same and len(res.data.vertices) == st.n_points:
        if np.array_equal(st.positions, X) and (normals is None or np.array_equal(st.normals, normals)):
            return SyncResult("unchanged")
        if normals is None and np.all(np.isfinite(X)):  # (normals: not linear in X)
            mesh_io.write_positions(res.data, _apply(st, X))
            st.positions = X
            st.update_seconds = time.perf_counter() - t0
            return SyncResult("updated")
    return _rebuild(obj, mod, res, settings, skey, X, offsets, corners, normals, progress, t0)


_PARTIAL_MAX_SHARE = 0.05  # partial update when the moved columns hold <= 5% of W's entries
_PARTIAL_REFRESH = 256  # full W @ X after this many partial updates (bounds round-off drift)
_SCAN_MAX_MOVED = 4  # up to this many moved vertices: find their entries by scanning W's
# column indices (0.45 ms per vertex on Suzanne r=16) instead of building the csc
# transpose (8-11 ms, which made the first drag step after a rebuild slow)


def _apply(st: SurfaceState, X: np.ndarray) -> np.ndarray:
    """Output points for new positions X: W @ X, or, when few vertices moved (an Edit
    Mode drag), P += W[:, moved] (X - X_old)[moved], touching only the samples in the
    moved vertices' supports (the same sum, regrouped; refreshed every
    ``_PARTIAL_REFRESH`` updates so round-off cannot accumulate). The moved columns'
    entries come from a scan of W's column indices for up to ``_SCAN_MAX_MOVED``
    vertices, else from the csc transpose (made once, on first need)."""
    moved = np.flatnonzero(np.any(X != st.positions, axis=1))
    if (st.points is not None and st.partial_updates < _PARTIAL_REFRESH
            and st.matrix_csc is None and 0 < len(moved) <= _SCAN_MAX_MOVED):
        W = st.matrix
        hit = W.indices == moved[0]
        for w in moved[1:]:
            hit |= W.indices == w
        pos = np.flatnonzero(hit)  # the entries of the moved columns, in row order
        if len(pos) <= _PARTIAL_MAX_SHARE * W.nnz:
            rows = np.searchsorted(W.indptr, pos, side="right") - 1
            delta = (X - st.positions)[W.indices[pos]]
            np.add.at(st.points, rows, W.data[pos, None] * delta)
            st.partial_updates += 1
            return st.points
    if st.points is not None and st.partial_updates < _PARTIAL_REFRESH:
        if st.matrix_csc is None:
            st.matrix_csc = st.matrix.tocsc()
        ptr = st.matrix_csc.indptr
        counts = ptr[moved + 1] - ptr[moved]
        total = int(counts.sum())
        if total <= _PARTIAL_MAX_SHARE * st.matrix_csc.nnz:
            # entry indices of the moved columns, concatenated
            idx = np.repeat(ptr[moved] - np.cumsum(counts) + counts, counts) + np.arange(total)
            delta = (X - st.positions)[np.repeat(moved, counts)]
            np.add.at(st.points, st.matrix_csc.indices[idx], st.matrix_csc.data[idx, None] * delta)
            st.partial_updates += 1
            return st.points
    st.points = _product(st.matrix, X, st.points)
    st.partial_updates = 0
    return st.points


def _product(W, X: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """W @ X as three sparse mat-vecs (measured 1.5x faster than scipy's csr @ (V, 3))."""
    XT = np.ascontiguousarray(X.T)
    if out is None or out.shape != (W.shape[0], 3):
        out = np.empty((W.shape[0], 3))
    for k in range(3):
        out[:, k] = W @ XT[k]
    return out


def _fail(obj, mod, key, st, message, progress) -> SyncResult:
    st.error, st.matrix = message, None
    _states[key] = st
    _set_error(obj, mod, message)
    progress(1.0, "error")
    return SyncResult("error", message)


def _rebuild(obj, mod, res, settings, skey, X, offsets, corners, normals, progress, t0):
    from gerbs_core.errors import GERBSValueError
    from gerbs_core.mesh_surface import BlendingSurface

    key = state_key(obj, mod)
    st = SurfaceState(settings=skey, offsets=offsets, corners=corners, positions=X,
                      normals=normals, result_uid=res.session_uid)
    progress(0.05, "building surface")
    lattice = None
    try:
        surface = BlendingSurface(
            X, mesh_io.faces_from_csr(offsets, corners), degree=settings["degree"],
            kernel=make_kernel(settings), mode=settings["mode"], boundary=settings["boundary"],
            normals=normals)
        if normals is None:
            progress(0.35, "building stencil")
            stencil = surface.stencil(settings["resolution"])
            st.matrix = stencil.matrix.tocsr()
            P, triangles, lattice = _product(st.matrix, X), stencil.triangles, stencil.lattice
        else:  # Hermite normals: not W @ X (the core refuses a stencil); evaluate directly
            progress(0.35, "evaluating surface")
            P, triangles, _ = surface.tessellate(settings["resolution"])
    except GERBSValueError as exc:
        return _fail(obj, mod, key, st, format_error(exc), progress)
    progress(0.8, "writing result mesh")
    if not np.all(np.isfinite(P)):
        bad = np.flatnonzero(~np.all(np.isfinite(P), axis=1))
        return _fail(obj, mod, key, st, (
            f"GERBS: internal error: the surface is not finite at {len(bad)} output points "
            f"(first {bad[:5].tolist()}); base mesh left as is"), progress)
    st.points = P
    st.triangles = np.asarray(triangles, dtype=np.int32)
    prev = _states.get(key)
    if (prev is not None and prev.triangles is not None and len(res.data.vertices) == len(P)
            and np.array_equal(prev.triangles, st.triangles)):
        mesh_io.write_positions(res.data, P)  # e.g. a new kernel: same output topology
    else:  # edges from the lattice structure where it has them (no hashing in Blender)
        mesh_io.write_surface(res.data, P, st.triangles,
                              edges=lattice.edges() if lattice is not None else None)
    _copy_materials(obj.data, res.data)
    if len(obj.data.materials) > 1:  # per-triangle material of the face it tessellates
        lattice = lattice or surface.lattice(settings["resolution"])
        tri_face = lattice.triangle_face
        mesh_io.write_material_indices(res.data, mesh_io.read_material_indices(obj.data)[tri_face])
    st.n_points, st.n_triangles = len(P), len(st.triangles)
    st.build_seconds = time.perf_counter() - t0
    _states[key] = st
    _set_error(obj, mod, "")
    progress(1.0, "done")
    return SyncResult("rebuilt")


def _copy_materials(base, result) -> None:
    if list(result.materials) != list(base.materials):
        result.materials.clear()
        for mat in base.materials:
            result.materials.append(mat)


def gerbs_objects():
    """Mesh objects carrying at least one GERBS modifier."""
    return [o for o in bpy.data.objects if o.type == "MESH" and gn.gerbs_modifiers(o)]


def sync_object(obj, *, force=False, progress=None) -> list[SyncResult]:
    return [sync(obj, mod, force=force, progress=progress) for mod in gn.gerbs_modifiers(obj)]


def collect_garbage() -> int:
    """Delete result objects no modifier uses any more (modifier removed or applied)."""
    removed = 0
    for res in list(bpy.data.objects):
        if res.get(ids.RESULT_TAG) and res.users == 0:
            mesh = res.data
            _owners.pop(res.session_uid, None)
            bpy.data.objects.remove(res)
            if mesh is not None and mesh.users == 0:
                bpy.data.meshes.remove(mesh)
            removed += 1
    alive = {state_key(o, m) for o in gerbs_objects() for m in gn.gerbs_modifiers(o)}
    for key in [k for k in _states if k not in alive]:
        del _states[key]
    return removed
