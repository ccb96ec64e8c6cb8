"""Building the node group behind the modifier (see geometry_nodes.py for why).

The group shows the hidden result object only while that result is *fresh*:
built from exactly the geometry the modifier receives now and with exactly the
current settings. Otherwise it passes its input through and says why::

    fresh = Error == ""
            and counts (V, F, C) == result's SNAP_COUNT
            and every position, corner vertex, face size and material index of the
                input == the result's SNAP_* attribute at the same index
            and every shape setting == its hidden "Built ..." input
    output = (result if fresh else input) without the SNAP_* attributes

The comparisons are exact (epsilon 0): the add-on stores the float32 values it
read, so any edit, however small, makes the result stale. This is what keeps a
stale surface from being shown, applied or exported when nothing updated the
result: a file opened without the add-on, a frame change the add-on missed,
``modifier_apply`` right after an edit. With the add-on running, the handlers
rebuild the result within the same depsgraph update and the second evaluation
shows it.

Node types missing in older Blender (the Warning node before 4.3, see
:mod:`compat`) are skipped: the switch logic does not depend on them.
"""
from __future__ import annotations

from . import compat, ids

MENU_NODE = "gerbs_menu_"  # name prefix of the Menu Switch nodes defining the menus


class _Tree:
    """Small helper: create nodes and links, find sockets by identifier."""

    def __init__(self, group):
        self.nodes, self.links = group.nodes, group.links

    def node(self, kind, **props):
        try:
            node = self.nodes.new(kind)
        except RuntimeError:  # node type unknown to this Blender version
            return None
        for name, value in props.items():
            setattr(node, name, value)
        return node

    @staticmethod
    def socket(sockets, identifier):
        return next(s for s in sockets if s.identifier == identifier)

    def link(self, src, dst):
        self.links.new(src, dst)

    def compare(self, data_type, operation, a, b):
        """Exact comparison of two sockets -> BOOLEAN output."""
        node = self.node("FunctionNodeCompare", data_type=data_type, operation=operation)
        suffix = {"FLOAT": "", "INT": "_INT", "VECTOR": "_VEC3", "STRING": "_STR"}[data_type]
        if data_type == "VECTOR":
            node.mode = "ELEMENT"
        if data_type in ("FLOAT", "VECTOR"):
            node.inputs["Epsilon"].default_value = 0.0
        for name, value in (("A", a), ("B", b)):
            sock = self.socket(node.inputs, name + suffix)
            if isinstance(value, (int, float, str)):
                sock.default_value = value
            else:
                self.link(value, sock)
        return node.outputs[0]

    def boolean(self, operation, *values):
        """AND/OR over any number of boolean outputs (NOT over one)."""
        out = values[0]
        if operation == "NOT":
            node = self.node("FunctionNodeBooleanMath", operation="NOT")
            self.link(out, node.inputs[0])
            return node.outputs[0]
        for value in values[1:]:
            node = self.node("FunctionNodeBooleanMath", operation=operation)
            self.link(out, node.inputs[0])
            self.link(value, node.inputs[1])
            out = node.outputs[0]
        return out

    def sample(self, geometry, name, data_type, domain, index):
        """The result's attribute `name` at `index` (a socket or an int)."""
        attr = self.node("GeometryNodeInputNamedAttribute", data_type=data_type)
        attr.inputs["Name"].default_value = name
        node = self.node("GeometryNodeSampleIndex", data_type=data_type, domain=domain)
        self.link(geometry, node.inputs["Geometry"])
        self.link(attr.outputs["Attribute"], node.inputs["Value"])
        if isinstance(index, int):
            node.inputs["Index"].default_value = index
        else:
            self.link(index, node.inputs["Index"])
        return node.outputs[0]

    def none_differ(self, geometry, domain, differs):
        """True when the boolean field `differs` is False on every element of `domain`."""
        stat = self.node("GeometryNodeAttributeStatistic", data_type="FLOAT", domain=domain)
        self.link(geometry, stat.inputs["Geometry"])
        self.link(differs, stat.inputs["Attribute"])
        return self.compare("FLOAT", "EQUAL", stat.outputs["Max"], 0.0)

    def warning(self, show, message, kind):
        """A node warning shown while `show` is True; returns `show` passed through it."""
        if not compat.has_node_type(compat.WARNING_NODE):  # Blender 4.2 (see compat)
            return show
        node = self.node(compat.WARNING_NODE, warning_type=kind)
        self.link(show, node.inputs["Show"])
        if isinstance(message, str):
            node.inputs["Message"].default_value = message
        else:
            self.link(message, node.inputs["Message"])
        return node.outputs["Show"]


def _new_socket(itf, spec: ids.SocketSpec):
    sock = itf.new_socket(spec.name, in_out="INPUT", socket_type=spec.socket_type)
    sock.description = spec.description
    if hasattr(sock, "structure_type") and spec.socket_type != "NodeSocketObject":
        try:
            sock.structure_type = "SINGLE"  # a setting, not a field: no attribute toggle
        except (TypeError, AttributeError):
            pass
    if spec.min is not None:
        sock.min_value = spec.min
    if spec.max is not None:
        sock.max_value = spec.max
    if spec.default is not None and spec.socket_type != "NodeSocketMenu":
        sock.default_value = spec.default
    sock.hide_in_modifier = spec.hidden
    return sock


def _menus(t: _Tree, gin, sockets) -> dict:
    """A Menu Switch per menu setting: it defines the menu's items (a menu input
    gets its items from the Menu Switch it is linked to) and outputs the chosen
    item's position (INT). Returns key -> that output."""
    out = {}
    for k, spec in enumerate(s for s in ids.SETTINGS if s.items):
        menu = t.node("GeometryNodeMenuSwitch", data_type="INT")
        menu.name = MENU_NODE + spec.key
        menu.enum_items.clear()
        for label in spec.items.values():
            menu.enum_items.new(label)
        for value, sock in enumerate(s for s in menu.inputs if s.identifier.startswith("Item_")):
            sock.default_value = value
        t.link(gin.outputs[spec.name], menu.inputs["Menu"])
        menu.location = (-200, -200 - 150 * k)
        sockets[spec.key].default_value = spec.items[spec.default]  # items exist once linked
        out[spec.key] = menu.outputs[0]
    return out


def _settings_fresh(t: _Tree, gin, menus):
    checks = []
    for spec, built in zip(ids.SHAPE_SETTINGS, ids.BUILT):
        current = menus.get(spec.key, gin.outputs[spec.name])
        kind = "FLOAT" if built.socket_type == "NodeSocketFloat" else "INT"
        checks.append(t.compare(kind, "EQUAL", current, gin.outputs[built.name]))
    return t.boolean("AND", *checks)


def _geometry_fresh(t: _Tree, base, result):
    """Exact equality of the base geometry with the snapshot stored on the result."""
    size = t.node("GeometryNodeAttributeDomainSize", component="MESH")
    t.link(base, size.inputs["Geometry"])
    checks = [t.compare("INT", "EQUAL", size.outputs[name],
                        t.sample(result, ids.SNAP_COUNT, "INT", "POINT", k))
              for k, name in enumerate(("Point Count", "Face Count", "Face Corner Count"))]
    index = t.node("GeometryNodeInputIndex").outputs[0]
    position = t.node("GeometryNodeInputPosition").outputs[0]
    checks.append(t.none_differ(base, "POINT", t.compare(
        "VECTOR", "NOT_EQUAL", position,
        t.sample(result, ids.SNAP_POSITION, "FLOAT_VECTOR", "POINT", index))))
    corner_vert = t.node("GeometryNodeVertexOfCorner")
    t.link(index, corner_vert.inputs["Corner Index"])
    checks.append(t.none_differ(base, "CORNER", t.compare(
        "INT", "NOT_EQUAL", corner_vert.outputs[0],
        t.sample(result, ids.SNAP_CORNER, "INT", "CORNER", index))))
    face_corners = t.node("GeometryNodeCornersOfFace")
    t.link(index, face_corners.inputs["Face Index"])
    material = t.node("GeometryNodeInputMaterialIndex").outputs[0]
    for value, name in ((face_corners.outputs["Total"], ids.SNAP_FACE_SIZE),
                        (material, ids.SNAP_MATERIAL)):
        checks.append(t.none_differ(base, "FACE", t.compare(
            "INT", "NOT_EQUAL", value, t.sample(result, name, "INT", "FACE", index))))
    return t.boolean("AND", *checks)


def _strip_snapshot(t: _Tree, geometry):
    """`geometry` without the SNAP_* attributes (they must not reach Apply or exports).

    One wildcard removal where the node has a pattern mode (it warns about no
    missing name); else one exact removal per name."""
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
    for name in ids.SNAPSHOT_ATTRIBUTES:
        remove = t.node("GeometryNodeRemoveAttribute")
        remove.inputs["Name"].default_value = name
        t.link(geometry, remove.inputs["Geometry"])
        geometry = remove.outputs[0]
    return geometry


def build(group) -> None:
    """Fill an empty Geometry Nodes group with the interface and the tree above."""
    itf = group.interface
    itf.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    itf.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    sockets = {spec.key: _new_socket(itf, spec) for spec in ids.INTERNAL + ids.SETTINGS + ids.BUILT}
    t = _Tree(group)
    gin, gout = t.node("NodeGroupInput"), t.node("NodeGroupOutput")
    info = t.node("GeometryNodeObjectInfo", transform_space="ORIGINAL")  # base object's space
    t.link(gin.outputs["Result"], info.inputs["Object"])
    base, result = gin.outputs["Geometry"], info.outputs["Geometry"]
    fresh = t.boolean("AND", _settings_fresh(t, gin, _menus(t, gin, sockets)),
                      _geometry_fresh(t, base, result))
    has_error = t.warning(t.compare("STRING", "NOT_EQUAL", gin.outputs["Error"], ""),
                          gin.outputs["Error"], "ERROR")
    no_error = t.boolean("NOT", has_error)
    stale = t.warning(t.boolean("AND", no_error, t.boolean("NOT", fresh)), ids.STALE_MESSAGE,
                      "WARNING")
    repaired = t.warning(t.boolean("AND", no_error, fresh, t.compare(
        "STRING", "NOT_EQUAL", gin.outputs["Warning"], "")), gin.outputs["Warning"], "WARNING")
    used = t.boolean("OR", repaired, t.boolean("NOT", repaired))  # (evaluates the warning)
    switch = t.node("GeometryNodeSwitch", input_type="GEOMETRY")
    t.link(t.boolean("AND", no_error, t.boolean("NOT", stale), used), switch.inputs["Switch"])
    t.link(base, switch.inputs["False"])
    t.link(_strip_snapshot(t, result), switch.inputs["True"])
    t.link(switch.outputs[0], gout.inputs[0])
    for node, xy in ((gin, (-900, 0)), (info, (-600, 300)), (switch, (600, 0)), (gout, (1400, 0))):
        node.location = xy
