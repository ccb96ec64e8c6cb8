"""The attributes a GERBS surface carries from its input mesh, read into numpy.

A :class:`Carried` holds every layer the surface carries (``ids.CARRIED_TYPES`` on
any domain: UV maps, color attributes, custom attributes, ``material_index``,
``sharp_face``, ``sharp_edge``, ``uv_seam``, ...; never ``position``,
``custom_normal`` or names starting with "."), the vertex-group weights (one FLOAT
POINT layer per group of the object, in the object's order) and which UV map and
color attribute are active. How each reaches the output is :mod:`transfer`.

Reading follows mesh_io's rule: only evaluated meshes, the final mesh, or the
add-on's own temporary copies are read, never the user's original mesh.
Vertex-group weights are read from the hidden ``ids.CHANNEL_WEIGHT`` attributes the
node group passes on when they are there (one ``foreach_get``), else vertex by
vertex (about 2.5 us a vertex).

Shapes: ``values (n, width)`` with n the element count of the layer's domain, width
and numpy type from ``ids.CARRIED_TYPES`` (colors RGBA; byte colors as sRGB floats
i/255, which round-trip exactly).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import ids, mesh_io


@dataclass(frozen=True, eq=False)
class Layer:
    """One carried attribute of the input (a vertex group when ``group``)."""

    name: str
    domain: str  # ids.DOMAINS
    data_type: str  # key of ids.CARRIED_TYPES
    values: np.ndarray  # (n, width)
    group: bool = False

    @property
    def key(self) -> tuple:
        return (self.name, self.domain, self.data_type, self.group)

    @property
    def branch(self) -> int:
        """The node group's check of this layer: kind x domain (ids.LAYER_KINDS, DOMAINS)."""
        return ids.CARRIED_TYPES[self.data_type][3] * len(ids.DOMAINS) + \
            ids.DOMAINS.index(self.domain)


@dataclass(frozen=True, eq=False)
class Carried:
    """Everything the surface carries besides positions and topology."""

    layers: tuple = ()
    edge_verts: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int32))
    active_uv: str = ""
    render_uv: str = ""
    active_color: str = ""
    default_color: str = ""
    # the crease layers (ids.CREASE_LAYERS names) the mesh has, whatever their type: the
    # record says which (the node group finds an input with another one stale)
    creases: tuple = ()

    @property
    def groups(self) -> tuple:
        """Vertex-group names in the object's order."""
        return tuple(layer.name for layer in self.layers if layer.group)

    def keys(self) -> tuple:
        return tuple(layer.key for layer in self.layers)

    def same(self, other) -> bool:
        """Same layers with equal values and the same active maps (the same object: the
        node group found its values equal, stack.read_input). Values compare as the node
        group does (:func:`values_equal`)."""
        if other is self:
            return True
        return (other is not None and self.keys() == other.keys()
                and self.flags() == other.flags()
                and np.array_equal(self.edge_verts, other.edge_verts)
                and all(values_equal(a.values, b.values)
                        for a, b in zip(self.layers, other.layers)))

    def flags(self) -> tuple:
        return (self.active_uv, self.render_uv, self.active_color, self.default_color,
                self.creases)


def values_equal(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the values a, b (n, width) of a layer are equal as the node group compares
    them (node_fresh): integers and booleans exactly, floats within ids.LAYER_TOLERANCE
    (1 + |b_i|) in every component (|b_i| the row's length; -0.0 == +0.0; a NaN or an
    infinity never equal)."""
    if a.shape != b.shape:
        return False
    if a.dtype.kind != "f":
        return bool(np.array_equal(a, b))
    with np.errstate(invalid="ignore", over="ignore"):
        tol = ids.LAYER_TOLERANCE * (1.0 + np.linalg.norm(b.astype(np.float64), axis=-1,
                                                        keepdims=True))
        return bool(np.all(np.abs(a.astype(np.float64) - b) <= tol))


def carried_name(name: str) -> bool:
    """Is an attribute of this name carried (if its type is)?"""
    return not name.startswith(".") and name not in ids.NOT_CARRIED


def _read(attr, n: int) -> np.ndarray:
    prop, width, dtype, _ = ids.CARRIED_TYPES[attr.data_type]
    buf = np.empty(n * width, dtype=dtype)
    attr.data.foreach_get(prop, buf)
    return buf.reshape(n, width)


def _domain_size(mesh, domain: str) -> int:
    return {"POINT": len(mesh.vertices), "EDGE": len(mesh.edges), "FACE": len(mesh.polygons),
            "CORNER": len(mesh.loops)}[domain]


def _carried_attributes(mesh, skip=()):
    """The attributes of `mesh` that are carried, in the mesh's order."""
    for attr in mesh.attributes:
        if (carried_name(attr.name) and attr.name not in skip
                and attr.data_type in ids.CARRIED_TYPES and attr.domain in ids.DOMAINS):
            yield attr


def attribute_layers(mesh, skip=()) -> list:
    """The carried attribute layers of `mesh` (an evaluated or add-on-owned mesh)."""
    return [Layer(a.name, a.domain, a.data_type, _read(a, _domain_size(mesh, a.domain)))
            for a in _carried_attributes(mesh, skip)]


def layer_keys(mesh, group_names) -> tuple:
    """The ``Carried.keys()`` :func:`read_carried` would give (no values read)."""
    return tuple((a.name, a.domain, a.data_type, False)
                 for a in _carried_attributes(mesh, set(group_names))) + \
        tuple((name, "POINT", "FLOAT", True) for name in group_names)


def flags_of(mesh) -> tuple:
    """``Carried.flags()`` of `mesh`: its active and render UV maps, active and default
    color attributes, and the crease layers it has (any type: one of a type the surface
    does not carry is still recorded as there, so the node group's check holds)."""
    uv, render = mesh.uv_layers.active, next((u for u in mesh.uv_layers if u.active_render), None)
    attrs = mesh.attributes
    return (uv.name if uv is not None else "", render.name if render is not None else "",
            getattr(attrs, "active_color_name", "") or "",
            getattr(attrs, "default_color_name", "") or "",
            tuple(name for name, _ in ids.CREASE_LAYERS if attrs.get(name) is not None))


def group_weights(mesh, n_groups: int, channel: dict | None = None) -> np.ndarray:
    """(V, n_groups) float32 weights of the mesh's vertex groups (0 where a vertex is not
    in a group). `channel`: group index -> name of a POINT FLOAT attribute holding its
    weights (the node group's ``ids.CHANNEL_WEIGHT``); the other groups are read vertex
    by vertex."""
    V = len(mesh.vertices)
    out = np.zeros((V, n_groups), dtype=np.float32)
    channel = channel or {}
    missing = False
    for g in range(n_groups):
        attr = mesh.attributes.get(channel[g]) if g in channel else None
        if attr is not None and attr.domain == "POINT" and attr.data_type == "FLOAT":
            attr.data.foreach_get("value", out[:, g])
        else:
            missing = True
    if missing and n_groups:
        done = {g for g in range(n_groups)
                if g in channel and mesh.attributes.get(channel[g]) is not None}
        for v in mesh.vertices:
            for elem in v.groups:
                if elem.group < n_groups and elem.group not in done:
                    out[v.index, elem.group] = elem.weight
    return out


def read_carried(mesh, group_names, channel: dict | None = None) -> Carried:
    """Everything `mesh` carries. `group_names`: the object's vertex groups in order
    (a mesh's deform weights refer to them by index)."""
    layers = attribute_layers(mesh, skip=set(group_names))
    weights = group_weights(mesh, len(group_names), channel)
    layers += [Layer(name, "POINT", "FLOAT", weights[:, [g]].copy(), group=True)
               for g, name in enumerate(group_names)]
    return Carried(tuple(layers), mesh_io.read_edge_verts(mesh), *flags_of(mesh))


def names_of(mesh, group_names) -> set:
    """The names `read_carried` would carry from `mesh` (no values read)."""
    return {a.name for a in _carried_attributes(mesh)} | set(group_names)
