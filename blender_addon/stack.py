"""What the modifier receives from the stack, read without touching the user's mesh.

The modifier builds on exactly what Blender delivers to it: shape keys with their
values, vertex-group masks and Edit Mode display (the active key, or the mix
with "Shape Key Edit Mode"), animation and drivers, and every modifier above it.
Reading it never touches the user's mesh (mesh_io): it comes from

* the final mesh, when every enabled modifier below GERBS only moves vertices
  (``ids.DEFORM_ONLY``: Armature, Lattice, ...) or there is none: while the node
  group shows no surface it passes its input on with the positions (its vertex
  normals with Use Custom Normals, and its vertex-group weights) it received copied
  into hidden attributes (node_fresh.channel), which those modifiers leave alone (the
  final mesh's own normals are those of the moved positions, never read); while it
  shows a result the final mesh carries no such attribute and the input is the
  result's record (the node group checked it equal);
* otherwise (a modifier below that changes the mesh, e.g. Triangulate), the mesh
  data-block as evaluated (its BMesh, copied in C, in Edit Mode): that is what the
  modifier receives only with no shape keys and no modifier above it; else the
  modifier refuses with a message naming them.
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace

import numpy as np

from . import attributes, ids, mesh_io, snapshot
from .errors import PREFIX

FRESH = "fresh"  # read_input: the modifier shows a result (its record is the input)
# how often read_input read everything ("full") or only the positions ("positions": the
# channel says the topology and layers are the record's); tests count with it
reads: Counter = Counter()


@dataclass(frozen=True)
class Stack:
    """The enabled modifiers around the GERBS modifier for one evaluation."""

    above: tuple
    after: tuple
    enabled: bool  # the GERBS modifier itself is evaluated
    render: bool
    edit: bool

    @property
    def deform_after(self) -> bool:
        return all(m.type in ids.DEFORM_ONLY for m in self.after)


def _enabled(mod, edit: bool, render: bool) -> bool:
    return (mod.show_render if render else mod.show_viewport) and (
        not edit or mod.show_in_editmode)


def stack_of(obj, mod, render: bool) -> Stack:
    edit = mesh_io.editing(obj) and not render
    mods = list(obj.modifiers)
    k = mods.index(mod)
    return Stack(tuple(m for m in mods[:k] if _enabled(m, edit, render)),
                 tuple(m for m in mods[k + 1:] if _enabled(m, edit, render)),
                 _enabled(mod, edit, render), render, edit)


def group_names(obj) -> list:
    return [g.name for g in obj.vertex_groups]


def _channel_vectors(final, name):
    """(V, 3) float32 of the channel's POINT FLOAT_VECTOR attribute `name`, or None."""
    attr = final.attributes.get(name)
    if attr is None or attr.domain != "POINT" or attr.data_type != "FLOAT_VECTOR":
        return None
    out = np.empty((len(final.vertices), 3), dtype=np.float32)
    attr.data.foreach_get("vector", out.ravel())
    return out


def shows_input(obj, mod, depsgraph) -> bool | None:
    """In `depsgraph`'s last evaluation, did `mod` pass its input on (the base mesh shows:
    an error, or a surface out of date, e.g. with Live Update off)? True / False where the
    final mesh can tell (only deform-only modifiers after GERBS, which keep the channel the
    node group writes when it passes its input on), None where it cannot (a modifier after
    GERBS that makes new geometry, the modifier not evaluated). Reads one attribute's
    presence; writes nothing, forces no evaluation."""
    st = stack_of(obj, mod, depsgraph.mode == "RENDER")
    if not st.enabled or not st.deform_after:
        return None
    obj_eval = obj.evaluated_get(depsgraph)
    if not obj_eval.is_evaluated or st.edit:
        return None
    attr = obj_eval.data.attributes.get(ids.CHANNEL_POSITION)
    return attr is not None and attr.domain == "POINT"


def _read_final(final, groups, use_normals, known, record):
    """The input from the channel on the final mesh: FRESH where it has none; None where
    it lacks the normals asked for (evaluated with other settings than those read)."""
    positions = _channel_vectors(final, ids.CHANNEL_POSITION)
    if positions is None:
        return FRESH
    # the input's normals: the final mesh's own are those of the positions moved below
    normals = _channel_vectors(final, ids.CHANNEL_NORMAL) if use_normals else None
    if use_normals and normals is None:
        return None
    named = _channel_serial(final)
    kept = _kept(final, groups, normals, positions, record, named)
    if kept is not None:
        reads["positions"] += 1
        return kept
    reads["full"] += 1
    # the channel's face sizes only where the group stored them in this evaluation
    # (serial -1): while it names a record it passes the mesh's own attributes on, and a
    # mesh may carry a stale copy of that attribute (an old Apply)
    stored = named is not None and named[0] == -1
    sizes = mesh_io.read_face_ints(final, ids.CHANNEL_FACE_SIZE) if stored else None
    inp = replace(mesh_io.read_mesh(final, False, positions, sizes), normals=normals)
    channel = _group_channel(known, groups)
    return inp.with_carried(attributes.read_carried(final, groups, channel))


def _channel_serial(final) -> tuple | None:
    """The record serial the node group put into the channel (ids.CHANNEL_RECORD + k,
    first point; -1s: it named no record and stored the face sizes), or None where the
    channel has none."""
    out = []
    for k in range(len(ids.SERIAL_NAMES)):
        attr = final.attributes.get(f"{ids.CHANNEL_RECORD}{k}")
        if attr is None or attr.domain != "POINT" or attr.data_type != "INT" or not len(attr.data):
            return None
        out.append(attr.data[0].value)
    return tuple(out)


def _kept(final, groups, normals, positions, record, named):
    """`record`'s input with these positions and `normals` (the channel's, or None), when
    the channel says the input's counts, topology, material indices, edges and recorded
    layers equal the record of that stamp (`named`: the serial the node group, which
    compared them, put into the channel), and the mesh has the same layers and active
    maps; else None (read everything). `record`: (input, stamp) the viewport result's
    state wrote, or None."""
    if record is None or record[0] is None or record[0].carried is None:
        return None
    inp, want = record[0], snapshot.serial(record[1])
    if want == (0, 0) or len(positions) != len(inp.positions) or named != want:
        return None
    carried = inp.carried
    if (attributes.layer_keys(final, groups) != carried.keys()
            or attributes.flags_of(final) != carried.flags()):
        return None
    return replace(inp, positions=positions, normals=normals)


def _group_channel(known, groups) -> dict:
    """group index (in `groups`) -> channel attribute, for groups the last input had."""
    if known is None or known.carried is None:
        return {}
    out = {}
    for i, layer in enumerate(known.carried.layers):
        if layer.group and layer.name in groups:
            out[groups.index(layer.name)] = f"{ids.CHANNEL_WEIGHT}{i}"
    return out


def unhonoured_message(obj, stack: Stack) -> str:
    keys = obj.data.shape_keys
    parts = [f"modifier{'s' if len(stack.above) > 1 else ''} "
             f"{', '.join(m.name for m in stack.above)}" if stack.above else "",
             "shape keys" if keys is not None and len(keys.key_blocks) > 1 else ""]
    ignored = " and ".join(p for p in parts if p)
    below = ", ".join(m.name for m in stack.after if m.type not in ids.DEFORM_ONLY)
    return (f"{PREFIX}{below} below it changes the mesh, so GERBS cannot see what it "
            f"receives and would ignore the {ignored}; move {below} above GERBS or GERBS "
            f"last")


def read_input(obj, mod, depsgraph, normals: bool, known=None, record=None):
    """What `mod` receives now: ``(MeshInput with carried, "", passed_on)``, ``(FRESH, "",
    False)`` while it shows a result, ``(None, "", False)`` when it is not evaluated (or was
    with other settings), or ``(None, message, False)``. `passed_on`: the input was read
    from the channel, so the node group passed it on and shows the base mesh (the base
    mesh read directly, below a modifier that is not deform-only or not evaluated, says
    nothing about what is shown: False).
    `known`: the last input read (its vertex-group layers tell the channel's names);
    `record`: (input, stamp) of the viewport result's last record write, or None: while
    the channel says only positions differ from that record, only they are read (an
    Edit Mode drag reads 12 bytes a vertex instead of the whole mesh)."""
    stack = stack_of(obj, mod, depsgraph.mode == "RENDER")
    if not stack.enabled:
        return None, "", False
    groups = group_names(obj)
    obj_eval = obj.evaluated_get(depsgraph)
    if stack.deform_after and obj_eval.is_evaluated:
        final = obj_eval.to_mesh() if stack.edit else obj_eval.data
        try:
            inp = _read_final(final, groups, normals, known, record)
            return inp, "", inp is not None and inp is not FRESH
        finally:
            if stack.edit:
                obj_eval.to_mesh_clear()
    keys = obj.data.shape_keys
    if stack.above or (keys is not None and len(keys.key_blocks) > 1):
        return None, unhonoured_message(obj, stack), False
    return read_base(obj, depsgraph, normals), "", False


def read_base(obj, depsgraph, normals: bool, carried_only: bool = False):
    """The mesh data-block itself as evaluated (in Edit Mode its BMesh): the input when no
    shape key and no modifier above changes it."""
    groups = group_names(obj)
    if mesh_io.editing(obj):
        with mesh_io.edit_mesh_copy(obj.data) as tmp:
            return _base_of(tmp, groups, normals, carried_only)
    return _base_of(obj.data.evaluated_get(depsgraph), groups, normals, carried_only)


def _base_of(mesh, groups, normals, carried_only):
    carried = attributes.read_carried(mesh, groups)
    if carried_only:
        return carried
    return mesh_io.read_mesh(mesh, normals).with_carried(carried)


def base_names(obj, depsgraph) -> set:
    """The names the mesh data-block itself would carry (cheap: no values read; in Edit
    Mode the BMesh's layers, which is all the original mesh's attributes hold then)."""
    mesh = obj.data if mesh_io.editing(obj) else obj.data.evaluated_get(depsgraph)
    return attributes.names_of(mesh, group_names(obj))
