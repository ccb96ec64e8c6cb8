"""The node group's checks that a result is fresh, and what it passes on.

A result (the geometry of the hidden result object) is *fresh* when its record
(snapshot.py) equals, exactly, what the modifier receives now::

    counts (V, F, C, E) == the record's
    and every position, corner vertex, face size, material index and edge's vertices
        == the record's at the same index
    and every carried layer i: the input's attribute (name from "Attribute Names",
        domain and type from the result's layer table) exists and equals the record's
        values, element by element (a repeat zone over the layers; floats within
        ids.LAYER_TOLERANCE (1 + |value|), integers exactly)
    and every recorded setting == the current one ("resolution" the one asked for)
    and, with Use Custom Normals, every vertex normal == the record's (the Normal node
        on points is bit for bit the mesh's ``vertex_normals`` the add-on stored)

Also here: writing the carried vertex-group weights into the result's vertex groups
(Store Named Attribute into a name that is a vertex group of the geometry writes the
group), and the *channel*: while no surface is shown, the input passes on with its
positions (its vertex normals with Use Custom Normals, and its vertex-group weights)
copied into hidden attributes, which deform-only modifiers below GERBS leave alone, so
the add-on can read what GERBS received from the final mesh.

The public builders (:func:`fresh`, :func:`shown`, :func:`channel`) add one Group node
per check, using the nested groups (node_parts.py) they build on first use: one per
check, and one per layer type and domain for the layer comparison.
"""
from __future__ import annotations

from . import ids, node_parts

_GEO, _STR, _BOOL = "NodeSocketGeometry", "NodeSocketString", "NodeSocketBool"
_CHECK_TYPES = (("FLOAT_VECTOR", "VECTOR"), ("FLOAT_COLOR", "RGBA"), ("INT", "INT"))


def fresh(t, base, result, names, current: dict, resolution):
    """(Is `result` fresh for the input `base` (the three checks below, each a part)?,
    are the input's topology and recorded layers the record's (only positions may
    differ)?). `names`: the "Attribute Names" socket; `current`: setting key -> socket;
    `resolution`: the socket of the resolution this result is for."""
    values = {spec.name: resolution if spec.key == "resolution" else current[spec.key]
              for spec in ids.RECORD_SETTINGS}
    geometry = t.group(_geometry_part(), {"Base": base, "Result": result})
    layers = t.boolean("AND", t.group(_layers_part(), {"Base": base, "Result": result,
                                                       "Names": names})["Fresh"],
                       t.group(_creases_part(), {"Base": base, "Result": result})["Fresh"])
    normals = t.group(_normals_part(), {"Base": base, "Result": result,
                                        "Use": current["use_normals"]})["Fresh"]
    return (t.boolean("AND", t.group(_settings_part(), {"Result": result, **values})["Fresh"],
                      geometry["Fresh"], layers, normals),
            t.boolean("AND", geometry["Topology"], layers))


def _settings_part():
    """Inputs: the result and every recorded setting as a float (as the check compares)."""
    def build(t, gin, gout):
        current = {s.key: gin[s.name] for s in ids.RECORD_SETTINGS}
        t.link(settings_fresh(t, gin["Result"], current), gout["Fresh"])
    inputs = [("Result", _GEO)] + [(s.name, "NodeSocketFloat") for s in ids.RECORD_SETTINGS]
    return node_parts.ensure("Settings Fresh", inputs, [("Fresh", _BOOL)], build)


def _geometry_part():
    def build(t, gin, gout):
        topology = topology_fresh(t, gin["Base"], gin["Result"])
        t.link(t.boolean("AND", topology, positions_fresh(t, gin["Base"], gin["Result"])),
               gout["Fresh"])
        t.link(topology, gout["Topology"])
    return node_parts.ensure("Geometry Fresh", [("Base", _GEO), ("Result", _GEO)],
                             [("Fresh", _BOOL), ("Topology", _BOOL)], build)


def _normals_part():
    """Inputs: base, result and Use Custom Normals: the normals are checked only then (a
    lazy Switch: Blender computes no normals otherwise)."""
    def build(t, gin, gout):
        t.link(t.switch("BOOLEAN", gin["Use"], True,
                        normals_fresh(t, gin["Base"], gin["Result"])), gout["Fresh"])
    return node_parts.ensure("Normals Fresh", [("Base", _GEO), ("Result", _GEO), ("Use", _BOOL)],
                             [("Fresh", _BOOL)], build)


def _layers_part():
    return node_parts.ensure(
        "Layers Fresh", [("Base", _GEO), ("Result", _GEO), ("Names", _STR)], [("Fresh", _BOOL)],
        lambda t, gin, gout: t.link(layers_fresh(t, gin["Base"], gin["Result"], gin["Names"]),
                                    gout["Fresh"]))


def _creases_part():
    """No crease layer the record lacks: creases shape the surface, and a layer added
    after the build is not among the recorded ones the layer check compares (found by an
    adversarial test: crease_edge added with Live Update off, or in a file opened without
    the add-on, left the uncreased surface shown, 0.43 off a fresh build)."""
    def build(t, gin, gout):
        checks = []
        for k, (name, domain) in enumerate(ids.CREASE_LAYERS):
            recorded = t.compare("INT", "EQUAL", t.sample(gin["Result"], f"{ids.SNAP_CREASED}{k}",
                                                          "INT", "POINT", 0), 1)
            new = t.boolean("AND", t.named(name, "FLOAT")[1], t.boolean("NOT", recorded))
            checks.append(t.none_differ(gin["Base"], domain, new))
        t.link(t.boolean("AND", *checks), gout["Fresh"])
    return node_parts.ensure("Creases Fresh", [("Base", _GEO), ("Result", _GEO)],
                             [("Fresh", _BOOL)], build)


def _layer_equal_part(kind, domain):
    def build(t, gin, gout):
        t.link(_layer_equal(t, gin["Base"], gin["Result"], gin["Name"], gin["Record"], kind,
                            domain), gout["Equal"])
    inputs = [("Base", _GEO), ("Result", _GEO), ("Name", _STR), ("Record", _STR)]
    return node_parts.ensure(f"Layer Equal {_CHECK_TYPES[kind][0]} {domain}", inputs,
                             [("Equal", _BOOL)], build)


def settings_fresh(t, result, current: dict):
    """Every recorded setting equals the current one (`current`: key -> socket, the
    resolution the result is for under "resolution")."""
    checks = []
    for k, spec in enumerate(ids.RECORD_SETTINGS):
        value = current[spec.key]
        checks.append(t.compare("FLOAT", "EQUAL", value,
                                t.sample(result, f"{ids.SNAP_SETTINGS}{k}", "FLOAT", "POINT", 0)))
    return t.boolean("AND", *checks)


def _differs(t, compare, value, stored, epsilon=0.0):
    """`value` differs from `stored` or either is not a number: NOT(|a - b| <= epsilon)
    (the Compare node's EQUAL, element by element), which a NaN or an infinity on either
    side makes True; its NOT_EQUAL, |a - b| > 0, is False for a NaN and for equal
    infinities."""
    return t.boolean("NOT", t.compare(compare, "EQUAL", value, stored, epsilon))


def _layer_epsilon(t, stored):
    """ids.LAYER_TOLERANCE (1 + |stored|): the carried float layers' tolerance (a vector's or
    color's length; infinite or NaN for a non-finite record, which then never equals)."""
    length = t.node("ShaderNodeVectorMath", operation="LENGTH")
    t.link(stored, length.inputs[0])
    return t.math("MULTIPLY_ADD", length.outputs["Value"], ids.LAYER_TOLERANCE, ids.LAYER_TOLERANCE)


def positions_fresh(t, base, result):
    """Every position of the base equals the record's, as floats compare (-0.0 equals
    +0.0; a NaN or an infinity never equals, :func:`_differs`)."""
    position = t.node("GeometryNodeInputPosition").outputs[0]
    return t.none_differ(base, "POINT", _differs(
        t, "VECTOR", position,
        t.sample(result, ids.SNAP_POSITION, "FLOAT_VECTOR", "POINT", t.index())))


def _normal(t):
    """The Normal node's output (on points: the mesh's ``vertex_normals``, custom normals
    included from Blender 4.5)."""
    return t.node("GeometryNodeInputNormal").outputs[0]


def normals_fresh(t, base, result):
    """Every vertex normal of the base equals the record's, as floats compare (as
    :func:`positions_fresh`)."""
    return t.none_differ(base, "POINT", _differs(
        t, "VECTOR", _normal(t),
        t.sample(result, ids.SNAP_NORMAL, "FLOAT_VECTOR", "POINT", t.index())))


def topology_fresh(t, base, result):
    """Exact equality of everything but the positions of the base geometry with the
    record on the result: counts, corner vertices, face sizes, material indices, edges."""
    size = t.node("GeometryNodeAttributeDomainSize", component="MESH")
    t.link(base, size.inputs["Geometry"])
    counts = ("Point Count", "Face Count", "Face Corner Count", "Edge Count")
    checks = [t.compare("INT", "EQUAL", size.outputs[name],
                        t.sample(result, f"{ids.SNAP_COUNT}{k}", "INT", "POINT", 0))
              for k, name in enumerate(counts)]
    index = t.index()
    corner_vert = t.node("GeometryNodeVertexOfCorner")
    t.link(index, corner_vert.inputs["Corner Index"])
    checks.append(t.none_differ(base, "CORNER", t.compare(
        "INT", "NOT_EQUAL", corner_vert.outputs[0],
        t.sample(result, ids.SNAP_CORNER, "INT", "CORNER", index))))
    face_corners = t.node("GeometryNodeCornersOfFace")
    t.link(index, face_corners.inputs["Face Index"])
    material = t.node("GeometryNodeInputMaterialIndex").outputs[0]
    # one pass over the faces for both (a face differs in its size or its material)
    checks.append(t.none_differ(base, "FACE", t.boolean("OR", *(t.compare(
        "INT", "NOT_EQUAL", value, t.sample(result, name, "INT", "FACE", index))
        for value, name in ((face_corners.outputs["Total"], ids.SNAP_FACE_SIZE),
                            (material, ids.SNAP_MATERIAL))))))
    ends = t.node("GeometryNodeInputMeshEdgeVertices")
    differ = t.boolean("OR", *(t.compare("INT", "NOT_EQUAL", ends.outputs[out],
                                         t.sample(result, name, "INT", "EDGE", index))
                               for out, name in (("Vertex Index 1", ids.SNAP_EDGE_A),
                                                 ("Vertex Index 2", ids.SNAP_EDGE_B))))
    checks.append(t.none_differ(base, "EDGE", differ))
    return t.boolean("AND", *checks)


def _layer(t, result, names, i):
    """(name, check branch, is a group) of carried layer `i` (a socket) of `result`."""
    row = [t.sample(result, ids.SNAP_LAYERS, "INT", "POINT", t.math("MULTIPLY_ADD", i, 4.0, k))
           for k in range(4)]
    return t.slice(names, row[0], row[1]), row[2], t.compare("INT", "EQUAL", row[3], 1)


def _count(t, result, k):
    return t.sample(result, f"{ids.SNAP_COUNT}{k}", "INT", "POINT", 0)


def _layer_equal(t, base, result, name, record, kind, domain):
    """The input's attribute `name` exists and equals the `record` attribute of `result`
    on `domain`, compared as the Named Attribute type of `kind`."""
    data_type, compare = _CHECK_TYPES[kind]
    value, exists = t.named(name, data_type)
    stored = t.sample(result, record, data_type, domain, t.index())
    unequal = _differs(t, compare, value, stored, _layer_epsilon(t, stored)) \
        if compare != "INT" else t.compare(compare, "NOT_EQUAL", value, stored)
    differs = t.boolean("OR", t.boolean("NOT", exists), unequal)
    return t.none_differ(base, domain, differs)


def layers_fresh(t, base, result, names):
    """Every carried layer recorded on `result` equals the input's (a repeat zone)."""
    zin, zout, inner = t.repeat(_count(t, result, 4), [("Fresh", "BOOLEAN", True),
                                                       ("Layer", "INT", 0)])
    i = inner["Layer"]
    name, branch, _ = _layer(t, result, names, i)
    record = t.string_join(ids.SNAP_LAYER, t.number_string(i))
    inputs = {"Base": base, "Result": result, "Name": name, "Record": record}
    checks = [t.group(_layer_equal_part(kind, domain), inputs)["Equal"]
              for kind in range(len(_CHECK_TYPES)) for domain in ids.DOMAINS]
    equal = t.index_switch("BOOLEAN", branch, checks)
    t.link(t.boolean("AND", inner["Fresh"], equal), zout.inputs["Fresh"])
    t.link(t.math("ADD", i, 1.0), zout.inputs["Layer"])
    return zout.outputs["Fresh"]


def _group_loop(t, geometry, table, names, target, source):
    """`geometry` with, for every vertex-group layer i of `table`'s record, the POINT
    FLOAT attribute ``target(i, name)`` := ``source(i, name)``."""
    zin, zout, inner = t.repeat(_count(t, table, 4), [("Geometry", "GEOMETRY", None),
                                                      ("Layer", "INT", 0)])
    t.link(geometry, zin.inputs["Geometry"])
    i = inner["Layer"]
    name, _, group = _layer(t, table, names, i)
    stored = t.store(inner["Geometry"], target(i, name), "FLOAT", "POINT", source(i, name))
    t.link(t.switch("GEOMETRY", group, inner["Geometry"], stored), zout.inputs["Geometry"])
    t.link(t.math("ADD", i, 1.0), zout.inputs["Layer"])
    return zout.outputs["Geometry"]


def shown(t, result, names):
    """A result as shown (a part): its weights in its vertex groups, its record removed."""
    return t.group(node_parts.ensure(
        "Shown", [("Result", _GEO), ("Names", _STR)], [("Geometry", _GEO)],
        lambda t, gin, gout: t.link(strip_record(t, with_groups(t, gin["Result"], gin["Names"])),
                                    gout["Geometry"])), {"Result": result, "Names": names})[0]


def channel(t, base, table, names, kept, normals):
    """:func:`channel_tree` as a part."""
    return t.group(node_parts.ensure(
        "Channel", [("Base", _GEO), ("Table", _GEO), ("Names", _STR), ("Kept", _BOOL),
                    ("Normals", _BOOL)],
        [("Geometry", _GEO)],
        lambda t, gin, gout: t.link(channel_tree(t, gin["Base"], gin["Table"], gin["Names"],
                                                 gin["Kept"], gin["Normals"]), gout["Geometry"])),
        {"Base": base, "Table": table, "Names": names, "Kept": kept, "Normals": normals})[0]


def with_groups(t, result, names):
    """The result with its carried weights (``ids.OUT_WEIGHT`` + i) in its vertex groups."""
    return _group_loop(
        t, result, result, names, target=lambda i, name: name,
        source=lambda i, name: t.named(t.string_join(ids.OUT_WEIGHT, t.number_string(i)),
                                       "FLOAT")[0])


def channel_tree(t, base, table, names, kept, normals):
    """The input as passed on while no surface is shown: its positions in
    ``ids.CHANNEL_POSITION``, its vertex normals in ``ids.CHANNEL_NORMAL`` when `normals`
    (Use Custom Normals; a Switch: not computed otherwise), in ``ids.CHANNEL_RECORD`` + k
    the serial of `table`'s record when `kept` (the input's topology and layers are that
    record's), else -1 and
    the face sizes in ``ids.CHANNEL_FACE_SIZE`` (a Switch: not computed when kept), and,
    for the vertex-group layers of `table`'s record, their weights in
    ``ids.CHANNEL_WEIGHT`` + i."""
    position = t.node("GeometryNodeInputPosition").outputs[0]
    geometry = t.store(base, ids.CHANNEL_POSITION, "FLOAT_VECTOR", "POINT", position)
    geometry = t.switch("GEOMETRY", normals, geometry, t.store(
        geometry, ids.CHANNEL_NORMAL, "FLOAT_VECTOR", "POINT", _normal(t)))
    for k, name in enumerate(ids.SERIAL_NAMES):
        serial = t.switch("INT", kept, -1, t.sample(table, name, "INT", "POINT", 0))
        geometry = t.store(geometry, f"{ids.CHANNEL_RECORD}{k}", "INT", "POINT", serial)
    sizes = t.node("GeometryNodeCornersOfFace")
    t.link(t.index(), sizes.inputs["Face Index"])
    geometry = t.switch("GEOMETRY", kept, t.store(geometry, ids.CHANNEL_FACE_SIZE, "INT", "FACE",
                                                  sizes.outputs["Total"]), geometry)
    return _group_loop(
        t, geometry, table, names,
        target=lambda i, name: t.string_join(ids.CHANNEL_WEIGHT, t.number_string(i)),
        source=lambda i, name: t.named(name, "FLOAT")[0])


def strip_record(t, geometry):
    """`geometry` without the record (it must not reach Apply or exports).

    One wildcard removal where the node has a pattern mode (it warns about no
    missing name); else one exact removal per fixed name (the per-layer records then
    stay, hidden)."""
    remove = t.node("GeometryNodeRemoveAttribute")
    mode = remove.inputs.get("Pattern Mode")
    if mode is not None or hasattr(remove, "pattern_mode"):
        if mode is not None:
            mode.default_value = "Wildcard"
        else:
            remove.pattern_mode = "WILDCARD"
        remove.inputs["Name"].default_value = ids.SNAPSHOT_PREFIX + "*"
        t.link(geometry, remove.inputs["Geometry"])
        return remove.outputs[0]
    t.nodes.remove(remove)
    for name in (ids.record_names() + ids.optional_record_names() + ids.SERIAL_NAMES
                 + (ids.SNAP_REST,)):
        remove = t.node("GeometryNodeRemoveAttribute")
        remove.inputs["Name"].default_value = name
        t.link(geometry, remove.inputs["Geometry"])
        geometry = remove.outputs[0]
    return geometry
