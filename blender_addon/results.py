"""The hidden result objects: creating them, and removing what no modifier uses.

Each GERBS modifier points at two result objects through its hidden "Result"
and "Render Result" inputs (that pointer is each object's only user, so they are
saved with the file and freed with the modifier). The result object and its mesh carry
``ids.RESULT_TAG``; the node group carries ``ids.GROUP_TAG``, the small groups it
uses (node_parts.py) ``ids.PART_TAG``. Garbage
collection removes tagged objects, meshes and groups with no users: a removed
or applied modifier, a deleted base object, a result object deleted by hand
(its mesh stays behind with no user).

Collecting scans ``bpy.data``, so the handlers run it only when something
that can leave garbage happened (see :class:`Watch`), never for an update of an
unrelated object.
"""
from __future__ import annotations

import logging

import bpy

from . import geometry_nodes as gn
from . import ids, node_parts

log = logging.getLogger(__name__)

_owners: dict[int, tuple] = {}  # result object's session_uid -> owning state key


def clear() -> None:
    _owners.clear()


def new_result_object(obj, render: bool = False):
    mesh = bpy.data.meshes.new(f"{ids.RENDER_RESULT_NAME if render else ids.RESULT_NAME} {obj.name}")
    mesh[ids.RESULT_TAG] = True
    res = bpy.data.objects.new(mesh.name, mesh)
    res[ids.RESULT_TAG] = True
    return res


def is_own(obj, res) -> bool:
    """May the sync write into `res`, the object `obj`'s modifier points at as its result?
    Only into the add-on's own: a local mesh object tagged ``ids.RESULT_TAG`` whose mesh
    is tagged too and used by it alone, neither `obj` nor `obj`'s mesh. Anything else --
    an object or mesh the user's (a Remap Users, a script setting the hidden input, the
    base object itself), a mesh another object uses too, library data (read-only) -- is
    never written."""
    if res is None or res.type != "MESH" or res == obj or not res.get(ids.RESULT_TAG):
        return False
    mesh = res.data
    return (mesh is not None and bool(mesh.get(ids.RESULT_TAG)) and mesh != obj.data
            and mesh.users == 1 and res.library is None and mesh.library is None)


def ensure_result(obj, mod, key: tuple, alive, render: bool = False) -> tuple[object, object]:
    """``(result, shown)``: the modifier's hidden result object (`render`: its render
    result), and the result object it pointed at until now -- what the evaluation that
    led to this sync showed (`result` itself, unless it was replaced; None if none).

    A new result is made if there is none, if the one pointed at is not the add-on's
    own (:func:`is_own`: it is left as it is, and the modifier points at the new one;
    safer than an error, which would leave the surface gone behind a hidden input the
    user cannot see to repair), or if the result belongs to another
    live modifier (``alive(owner_key)``): the object was duplicated with its
    modifier (Shift+D, Alt+D, ``obj.copy()``), and both now point at one result.
    The copy then builds its own; until its first build it shows the original's
    result, whose record is what the copy receives (the node group checked it), so
    `shown` is where the sync reads its input.
    """
    shown = res = gn.get_result(mod, render)
    if res is not None and not is_own(obj, res):
        log.warning("GERBS: %s: the modifier's hidden %s input pointed at %r, which is not "
                    "a GERBS result of its own; that object is left unchanged and a new "
                    "result is made", obj.name, "Render Result" if render else "Result",
                    res.name)
        res = None
    if res is not None:
        owner = _owners.get(res.session_uid)
        if owner is not None and owner != key and alive(owner):
            res = None
    if res is None:
        res = new_result_object(obj, render)
        gn.set_result(mod, res, render)
        # an ID property write does not tag depsgraph relations; re-assigning the
        # group through RNA does, so the new object is evaluated in this update
        mod.node_group = mod.node_group
    _owners[res.session_uid] = key
    return res, (shown if shown is not None and shown.type == "MESH" else None)


def collect_garbage() -> int:
    """Delete tagged result objects, meshes and node groups that nothing uses."""
    removed = 0
    for res in [o for o in bpy.data.objects if o.get(ids.RESULT_TAG) and o.users == 0]:
        _owners.pop(res.session_uid, None)
        mesh = res.data
        bpy.data.objects.remove(res)
        removed += 1
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)
    for mesh in [m for m in bpy.data.meshes if m.get(ids.RESULT_TAG) and m.users == 0]:
        bpy.data.meshes.remove(mesh)  # its object was deleted by hand
        removed += 1
    for group in [g for g in bpy.data.node_groups if gn.is_gerbs_group(g) and g.users == 0]:
        bpy.data.node_groups.remove(group)
        removed += 1
    removed += node_parts.collect_unused()  # the parts only the removed groups used
    if removed:
        log.debug("removed %d unused GERBS data-blocks", removed)
    return removed


class Watch:
    """Tells the handlers when data-blocks may have been deleted: the number of
    objects, meshes or node groups changed since the last look (counting a
    ``bpy.data`` collection is a C list walk, microseconds for thousands)."""

    def __init__(self):
        self._counts = None

    @staticmethod
    def _now():
        return len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.node_groups)

    def changed(self) -> bool:
        """Did the counts change since the last :meth:`changed` or :meth:`seen`?"""
        counts = self._now()
        changed, self._counts = counts != self._counts, counts
        return changed

    def seen(self) -> None:
        """Take the current counts as known (after the add-on's own additions)."""
        self._counts = self._now()
