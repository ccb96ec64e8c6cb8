"""The record of its input that every result mesh carries (what the node group checks).

A result shows only while the geometry the modifier receives equals the record,
exactly (node_fresh.py): positions, corner vertices, face sizes, material
indices, edge vertices, counts, every carried layer's values (``ids.SNAP_LAYER``
+ i, on the layer's own domain and type) and the settings the result was built
with (``ids.SNAP_SETTINGS`` + k, in ``ids.RECORD_SETTINGS`` order; counts and settings one
attribute each, on its first point). The names of the
carried layers travel as one string on the modifier ("Attribute Names"); the
result's ``ids.SNAP_LAYERS`` table says where each name starts, its length, how
the node group checks it and whether it is a vertex group. Each record uses the
first V / E / F / C elements of its domain (a result has at least as many).
"""
from __future__ import annotations

import itertools
import os

import numpy as np

from . import ids
from .attributes import Carried, Layer, flags_of
from .mesh_io import MeshInput, _get


# session salt: a stamp saved in a file from another session never equals one made here
_SALT = int.from_bytes(os.urandom(4), "little") % 0x7FFFFFFF + 1  # 1 .. 2^31 - 1 (int32)
_COUNTER = itertools.count(1)


def stamp(mesh) -> str:
    """Mark `mesh`'s record as just written: a stamp never used before in this session,
    stored on the mesh (a custom property: undo and file loads restore the stamp with
    the record) and returned. While the mesh still carries the stamp a state kept, its
    record is the input that state wrote (engine: no need to read it back).

    The same stamp as two ints (:func:`serial`) goes into ``ids.SERIAL_NAMES`` (first
    point), where the node group can see it: it passes it on in the channel when the
    input's topology and layers equal this record (stack.read_input)."""
    value = f"{os.getpid():x}.{_SALT}.{next(_COUNTER)}"
    mesh[ids.RECORD_STAMP] = value
    for name, part in zip(ids.SERIAL_NAMES, serial(value) if len(mesh.vertices) else ()):
        attr = mesh.attributes.get(name)
        if attr is None or attr.data_type != "INT" or attr.domain != "POINT":
            put(mesh, name, "INT", "POINT", [part], len(mesh.vertices))
        elif len(attr.data):
            attr.data[0].value = part  # one element: the node group reads only the first
    return value


def serial(value: str) -> tuple:
    """(salt, counter) of a stamp of this session, (0, 0) for anything else (no record
    write has salt 0)."""
    parts = value.split(".")
    if len(parts) != 3 or parts[1] != str(_SALT) or not parts[2].isdigit():
        return (0, 0)
    return (_SALT, int(parts[2]))


def stamp_of(mesh) -> str:
    return mesh.get(ids.RECORD_STAMP, "")


def put(mesh, name: str, data_type: str, domain: str, values, size: int) -> None:
    """Attribute `name` of `mesh` := `values` (n, width) in its first n elements, zeros
    after (created or re-created with this type and domain)."""
    attr = mesh.attributes.get(name)
    if attr is None or attr.data_type != data_type or attr.domain != domain:
        if attr is not None:
            mesh.attributes.remove(attr)
        attr = mesh.attributes.new(name, data_type, domain)
    prop, width, dtype, _ = ids.CARRIED_TYPES[data_type]
    buf = np.zeros(size * width, dtype=dtype)
    flat = np.ravel(values)
    buf[:len(flat)] = flat
    attr.data.foreach_set(prop, buf)


def layer_table(carried: Carried | None) -> tuple[str, np.ndarray]:
    """(the names string, (A, 4) int32 table: name start, length, check branch, group)."""
    layers = carried.layers if carried is not None else ()
    names, rows, start = [], [], 0
    for layer in layers:
        names.append(layer.name)
        rows.append((start, len(layer.name), layer.branch, int(layer.group)))
        start += len(layer.name)
    return "".join(names), np.array(rows, dtype=np.int32).reshape(-1, 4)


def _domain_sizes(mesh) -> dict:
    return {"POINT": len(mesh.vertices), "EDGE": len(mesh.edges), "FACE": len(mesh.polygons),
            "CORNER": len(mesh.loops)}


def misfit(mesh, inp: MeshInput) -> str:
    """"" when the record of `inp` fits on result `mesh` (each record uses the first
    V / E / F / C elements of its domain, the layer table the first 4 A points), else what
    the mesh has too few of and why, for a message after "the output at resolution r has":
    "8 points, fewer than the 12 its record of the input needs (4 for each of the 3 layers
    it carries: UV maps, vertex groups, attributes)"."""
    carried = inp.carried or Carried()
    n_layers = len(carried.layers)
    need = {"points": max(len(inp.positions), 4 * n_layers),
            "edges": len(carried.edge_verts), "faces": len(inp.offsets) - 1,
            "face corners": len(inp.corners)}
    have = dict(zip(need, (len(mesh.vertices), len(mesh.edges), len(mesh.polygons),
                           len(mesh.loops))))
    short = [k for k in need if have[k] < need[k]]
    if not short:
        return ""
    why = {k: f"the mesh has {need[k]} (loose or merged ones)" for k in short}
    if "points" in short and have["points"] < 4 * n_layers:
        # a stress test found the layer table's need reported as loose vertices
        why["points"] = (f"its record of the input needs {4 * n_layers} (4 for each of the "
                         f"{n_layers} layers it carries: UV maps, vertex groups, attributes)")
    return "; ".join(f"{have[k]} {k}, fewer than {why[k]}" for k in short)


_FEW = 64  # up to this many changed positions are written one by one (~1 us each)


def write_positions(mesh, inp: MeshInput, moved=None) -> str:
    """Only the positions (the fast path: nothing else changed); returns the new stamp.
    `moved`: (m,) the only vertices whose positions differ from the record on `mesh`
    (None: unknown): a few are written element by element instead of the whole
    attribute (a result has ~4 r^2 times more points than the record has vertices)."""
    attr = mesh.attributes.get(ids.SNAP_POSITION)
    if (moved is None or len(moved) > _FEW or attr is None or attr.domain != "POINT"
            or attr.data_type != "FLOAT_VECTOR"):
        put(mesh, ids.SNAP_POSITION, "FLOAT_VECTOR", "POINT", inp.positions, len(mesh.vertices))
    else:
        data = attr.data
        for i in moved.tolist():
            data[i].vector = inp.positions[i]
    return stamp(mesh)


def write_snapshot(mesh, inp: MeshInput, record) -> str:
    """Store `inp` (with its carried layers) and the settings `record` on the result;
    returns the new stamp."""
    n = _domain_sizes(mesh)
    carried = inp.carried or Carried()
    _, table = layer_table(carried)
    write_positions(mesh, inp)
    counts = (len(inp.positions), len(inp.offsets) - 1, len(inp.corners),
              len(carried.edge_verts), len(table))
    _put_scalars(mesh, ids.SNAP_COUNT, "INT", counts, n["POINT"])
    _put_scalars(mesh, ids.SNAP_CREASED, "INT",
                 [int(name in carried.creases) for name, _ in ids.CREASE_LAYERS], n["POINT"])
    put(mesh, ids.SNAP_CORNER, "INT", "CORNER", inp.corners, n["CORNER"])
    put(mesh, ids.SNAP_FACE_SIZE, "INT", "FACE", np.diff(inp.offsets), n["FACE"])
    put(mesh, ids.SNAP_MATERIAL, "INT", "FACE", inp.materials, n["FACE"])
    put(mesh, ids.SNAP_EDGE_A, "INT", "EDGE", carried.edge_verts[:, 0], n["EDGE"])
    put(mesh, ids.SNAP_EDGE_B, "INT", "EDGE", carried.edge_verts[:, 1], n["EDGE"])
    _put_scalars(mesh, ids.SNAP_SETTINGS, "FLOAT", record, n["POINT"])
    put(mesh, ids.SNAP_LAYERS, "INT", "POINT", table, n["POINT"])
    for i, layer in enumerate(carried.layers):
        put(mesh, f"{ids.SNAP_LAYER}{i}", layer.data_type, layer.domain, layer.values,
            n[layer.domain])
    for name in [a.name for a in mesh.attributes if a.name.startswith(ids.SNAP_LAYER)]:
        suffix = name[len(ids.SNAP_LAYER):]
        if not suffix.isdigit() or int(suffix) >= len(carried.layers):  # a layer gone since
            mesh.attributes.remove(mesh.attributes[name])
    if inp.normals is not None:
        put(mesh, ids.SNAP_NORMAL, "FLOAT_VECTOR", "POINT", inp.normals, n["POINT"])
    elif mesh.attributes.get(ids.SNAP_NORMAL) is not None:
        mesh.attributes.remove(mesh.attributes[ids.SNAP_NORMAL])
    return stamp(mesh)


def _creases(mesh, n) -> tuple:
    """The crease layers the record's input had (:attr:`Carried.creases`; none where the
    record predates them)."""
    attrs = mesh.attributes
    return tuple(name for k, (name, _) in enumerate(ids.CREASE_LAYERS)
                 if attrs.get(f"{ids.SNAP_CREASED}{k}") is not None
                 and _get(attrs[f"{ids.SNAP_CREASED}{k}"].data, "value", n["POINT"], np.int32)[0])


def _put_scalars(mesh, prefix: str, data_type: str, values, size: int) -> None:
    """Each of `values` on the first point of its own attribute `prefix` + k (a tiny
    output has fewer points than there are values)."""
    for k, value in enumerate(values):
        put(mesh, f"{prefix}{k}", data_type, "POINT", [value], size)


def _scalars(mesh, prefix: str, count: int, dtype) -> np.ndarray:
    """The values :func:`_put_scalars` stored (the attributes must exist)."""
    n = len(mesh.vertices)
    return np.array([_get(mesh.attributes[f"{prefix}{k}"].data, "value", n, dtype)[0]
                     for k in range(count)], dtype=dtype)


def record_topology(mesh) -> tuple | None:
    """(offsets (F+1,) int64, corners (C,) int32) of the input the record on `mesh` was
    written from, or None where it has no record (cheap: no layer, no position read)."""
    attrs = mesh.attributes
    names = [f"{ids.SNAP_COUNT}{k}" for k in range(3)] + [ids.SNAP_CORNER, ids.SNAP_FACE_SIZE]
    if any(attrs.get(name) is None for name in names) or not len(mesh.vertices):
        return None
    n = _domain_sizes(mesh)
    _, F, C = (int(c) for c in _scalars(mesh, ids.SNAP_COUNT, 3, np.int32))
    if not (0 <= F <= n["FACE"] and 0 <= C <= n["CORNER"]):
        return None
    sizes = _get(attrs[ids.SNAP_FACE_SIZE].data, "value", n["FACE"], np.int32)[:F]
    offsets = np.zeros(F + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    return offsets, _get(attrs[ids.SNAP_CORNER].data, "value", n["CORNER"], np.int32)[:C].copy()


def read_record(mesh) -> np.ndarray | None:
    """The settings record (len(ids.RECORD_SETTINGS),) float32, or None."""
    if any(mesh.attributes.get(name) is None for name in ids.record_names()) \
            or not len(mesh.vertices):
        return None
    return _scalars(mesh, ids.SNAP_SETTINGS, len(ids.RECORD_SETTINGS), np.float32)


def _read_layers(mesh, names: str, A: int, n: dict) -> tuple | None:
    attrs = mesh.attributes
    table = _get(attrs[ids.SNAP_LAYERS].data, "value", n["POINT"], np.int32)[:4 * A].reshape(A, 4)
    layers = []
    for i, (start, length, branch, group) in enumerate(table.tolist()):
        attr = attrs.get(f"{ids.SNAP_LAYER}{i}")
        name = names[start:start + length]
        if attr is None or len(name) != length or attr.data_type not in ids.CARRIED_TYPES:
            return None
        prop, width, dtype, _ = ids.CARRIED_TYPES[attr.data_type]
        size = n[attr.domain]
        buf = np.empty(size * width, dtype=dtype)
        attr.data.foreach_get(prop, buf)
        layers.append((name, attr.domain, attr.data_type, buf.reshape(size, width), bool(group)))
    return tuple(layers)


def read_snapshot(mesh, names: str) -> MeshInput | None:
    """The input stored by :func:`write_snapshot` (None if the mesh has none or it does
    not fit). `names`: the modifier's "Attribute Names"."""
    attrs = mesh.attributes
    if any(attrs.get(name) is None for name in ids.record_names() if name != ids.SNAP_NORMAL):
        return None
    n = _domain_sizes(mesh)
    if not n["POINT"]:
        return None
    V, F, C, E, A = (int(c) for c in _scalars(mesh, ids.SNAP_COUNT, ids.N_COUNTS, np.int32))
    if not (0 <= V <= n["POINT"] and 0 <= F <= n["FACE"] and 0 <= C <= n["CORNER"]
            and 0 <= E <= n["EDGE"] and 0 <= 4 * A <= n["POINT"]):
        return None
    raw = _read_layers(mesh, names, A, n)
    if raw is None:
        return None
    cut = {"POINT": V, "EDGE": E, "FACE": F, "CORNER": C}
    layers = tuple(Layer(name, d, t, v[:cut[d]].copy(), g) for name, d, t, v, g in raw)
    edge_verts = np.stack([_get(attrs[k].data, "value", n["EDGE"], np.int32)[:E]
                           for k in (ids.SNAP_EDGE_A, ids.SNAP_EDGE_B)], 1)
    # the result's active maps are the input's (carried); its crease layers are the record's
    carried = Carried(layers, edge_verts, *flags_of(mesh)[:4], _creases(mesh, n))
    sizes = _get(attrs[ids.SNAP_FACE_SIZE].data, "value", n["FACE"], np.int32)[:F]
    offsets = np.zeros(F + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    normals = attrs.get(ids.SNAP_NORMAL)
    return MeshInput(
        positions=_get(attrs[ids.SNAP_POSITION].data, "vector", n["POINT"], np.float32, 3)[:V].copy(),
        offsets=offsets,
        corners=_get(attrs[ids.SNAP_CORNER].data, "value", n["CORNER"], np.int32)[:C].copy(),
        materials=_get(attrs[ids.SNAP_MATERIAL].data, "value", n["FACE"], np.int32)[:F].copy(),
        normals=None if normals is None else
        _get(normals.data, "vector", n["POINT"], np.float32, 3)[:V].copy(),
        carried=carried)
