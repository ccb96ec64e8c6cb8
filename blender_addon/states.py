"""What the sync last built for each result: the per-modifier states (numpy data only,
never bpy references, so undo and file loads cannot leave dangling pointers), keyed by
``(object.session_uid, modifier.persistent_uid)`` ("render" appended for the render
result), and the outcome of a sync."""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from . import mesh_io


@dataclass
class SurfaceState:
    """What was last built for one result (numpy only)."""

    settings: tuple
    input: mesh_io.MeshInput
    positions: np.ndarray  # (V, 3) float64 of input.positions
    stencil: object = None  # gerbs_core.mesh.stencil.Stencil (P points from V positions)
    # build.Model: the BlendingSurface built (or reused) and the digest of its arguments;
    # a build with equal arguments at another resolution reuses it (engine._held_models)
    model: object = None
    rest: np.ndarray | None = None  # (V, 3) the rest shape the stencil is bound to
    transfer: object = None  # transfer.Transfer: the output's maps of carried layers
    points: np.ndarray | None = None  # (P, 3) float64 last output (for partial updates)
    points32: np.ndarray | None = None  # (P, 3) float32 the same, as written to the result
    record: tuple = ()  # the settings record written with the result
    stamp: str = ""  # snapshot.stamp of the record this state last wrote ("" none/failed)
    partial_updates: int = 0
    n_points: int = 0
    n_faces: int = 0  # output faces (quads in quad faces, triangles elsewhere)
    n_triangles: int = 0  # triangles of the same surface triangulated (e.g. as exported)
    result_uid: int = -1
    error: str = ""
    problem: object = None  # the InvalidMeshError behind `error` (select operator)
    build_seconds: float = 0.0
    surface_seconds: float = 0.0  # constructing the surface (held: its first build's)
    surface_held: bool = False  # the surface was held (a resolution change): not built
    update_seconds: float = 0.0
    warnings: tuple = ()  # gerbs_core.mesh.repair.MeshWarning of the last build


@dataclass(frozen=True)
class SyncResult:
    status: str  # "unchanged" | "updated" | "rebuilt" | "error"
    message: str = ""
    rebind: bool = False  # a linear preview of a Follow surface: rebuild when edits settle
    retry: bool = False  # the node group was made to pass its input on: sync again soon


states: dict[tuple, SurfaceState] = {}
# Rest Shape Bound: the rest shapes each modifier was bound to, one per topology (rest.py):
# an Edit Mode undo across a topology change restores the edit mesh, not the hidden result
# that stores the rest shape, so the earlier topology's binding is found here
bindings: dict[tuple, list] = {}
stats: Counter = Counter()  # how often each SyncResult status occurred (tests, panel)


def state_key(obj, mod, render: bool = False) -> tuple:
    key = (obj.session_uid, getattr(mod, "persistent_uid", mod.name))  # (name before 4.2)
    return key + ("render",) if render else key


def get_state(obj, mod, render: bool = False) -> SurfaceState | None:
    return states.get(state_key(obj, mod, render))


def known(obj) -> bool:
    """Has any modifier of `obj` been synced (so it may leave garbage behind)?"""
    uid = obj.session_uid
    return any(key[0] == uid for key in states)


def gone(alive_keys) -> set:
    """Session uids of the objects with a state whose modifier is not in `alive_keys`."""
    return {key[0] for key in states if key[:2] not in alive_keys}


def prune(alive_keys) -> None:
    """Drop the states of modifiers that no longer exist (render states with them)."""
    for key in [k for k in states if k[:2] not in alive_keys]:
        del states[key]
    for key in [k for k in bindings if k not in alive_keys]:
        del bindings[key]
