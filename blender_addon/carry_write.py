"""Writing the carried layers onto the result (the add-on's own object and mesh).

Attributes keep their names, types and domains (a FLOAT2 face-corner attribute is
a UV map); the active and render UV maps and the active and default color
attributes are set as on the input. Vertex groups: the result object gets the
input object's groups by name, in the same order (deform modifiers below GERBS
look groups up by name on the base object and by index in the mesh), and each
group's output weights go into the hidden ``ids.OUT_WEIGHT`` + i attribute, which
the node group stores into the group (node_fresh.with_groups): one array write
instead of a Python call per vertex.
"""
from __future__ import annotations

from . import ids
from .attributes import carried_name
from .snapshot import put


def _sizes(mesh) -> dict:
    return {"POINT": len(mesh.vertices), "EDGE": len(mesh.edges), "FACE": len(mesh.polygons),
            "CORNER": len(mesh.loops)}


def _sync_groups(res, names) -> None:
    if [g.name for g in res.vertex_groups] != list(names):
        res.vertex_groups.clear()
        for name in names:
            res.vertex_groups.new(name=name)


def write_layers(res, out_layers, carried) -> None:
    """Replace the carried layers of result object `res` by `out_layers`
    (transfer.OutputLayer, in the order of ``carried.layers``)."""
    mesh = res.data
    n = _sizes(mesh)
    names = set()
    for i, layer in enumerate(out_layers):
        if layer is None:
            continue
        if layer.group:
            put(mesh, f"{ids.OUT_WEIGHT}{i}", "FLOAT", "POINT", layer.values, n["POINT"])
        else:
            put(mesh, layer.name, layer.data_type, layer.domain, layer.values, n[layer.domain])
            names.add(layer.name)
    weights = {f"{ids.OUT_WEIGHT}{i}" for i, layer in enumerate(out_layers)
               if layer is not None and layer.group}
    for attr in [a.name for a in mesh.attributes]:
        gone = (carried_name(attr) and attr not in names) or \
            (attr.startswith(ids.OUT_WEIGHT) and attr not in weights)
        if gone:
            mesh.attributes.remove(mesh.attributes[attr])
    _sync_groups(res, carried.groups)
    _set_active(mesh, carried)


def _set_active(mesh, carried) -> None:
    uvs = mesh.uv_layers
    if carried.active_uv in uvs:
        uvs.active = uvs[carried.active_uv]
    if carried.render_uv in uvs:
        uvs[carried.render_uv].active_render = True
    attrs = mesh.attributes
    for prop, name in (("active_color_name", carried.active_color),
                       ("default_color_name", carried.default_color)):
        if name and hasattr(attrs, prop) and name in mesh.color_attributes:
            setattr(attrs, prop, name)
