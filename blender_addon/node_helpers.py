"""A small builder for the add-on's Geometry Nodes tree: nodes, links, comparisons,
samples and repeat zones, found by socket identifier (node_tree.py uses it).

Node types missing in older Blender (the Warning node before 4.3, see :mod:`compat`)
are skipped by :meth:`Tree.node`, which returns None for them.
"""
from __future__ import annotations

from . import compat


class Tree:
    """Create nodes and links in `group`; values are sockets or plain constants."""

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

    def feed(self, sock, value):
        """Link `value` (a socket) into `sock`, or set it as the default (a constant)."""
        if isinstance(value, (bool, int, float, str)):
            sock.default_value = value
        else:
            self.link(value, sock)

    def group(self, node_group, inputs: dict):
        """A Group node using `node_group`, its inputs fed from `inputs` (name -> value);
        returns its outputs."""
        node = self.node("GeometryNodeGroup")
        node.node_tree = node_group
        for name, value in inputs.items():
            self.feed(node.inputs[name], value)
        return node.outputs

    def compare(self, data_type, operation, a, b, epsilon=0.0):
        """Comparison of two values -> BOOLEAN output: exact, or for EQUAL / NOT_EQUAL of
        floats, vectors (per element) and colors within ``epsilon`` (a value or socket)."""
        node = self.node("FunctionNodeCompare", data_type=data_type, operation=operation)
        suffix = {"FLOAT": "", "INT": "_INT", "VECTOR": "_VEC3", "RGBA": "_COL",
                  "STRING": "_STR"}[data_type]
        if data_type == "VECTOR":
            node.mode = "ELEMENT"
        if data_type in ("FLOAT", "VECTOR", "RGBA"):
            self.feed(node.inputs["Epsilon"], epsilon)
        for name, value in (("A", a), ("B", b)):
            self.feed(self.socket(node.inputs, name + suffix), value)
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
            self.feed(node.inputs[0], out)
            self.feed(node.inputs[1], value)
            out = node.outputs[0]
        return out

    def math(self, operation, a, b=0.0, c=0.0):
        node = self.node("ShaderNodeMath", operation=operation)
        for sock, value in zip(node.inputs, (a, b, c)):
            self.feed(sock, value)
        return node.outputs[0]

    def named(self, name, data_type):
        """(Attribute, Exists) of the named attribute `name` (a string or a socket)."""
        node = self.node("GeometryNodeInputNamedAttribute", data_type=data_type)
        self.feed(node.inputs["Name"], name)
        return node.outputs["Attribute"], node.outputs["Exists"]

    def sample(self, geometry, name, data_type, domain, index):
        """The attribute `name` of `geometry` at `index` (a socket or an int)."""
        node = self.node("GeometryNodeSampleIndex", data_type=data_type, domain=domain)
        self.link(geometry, node.inputs["Geometry"])
        self.link(self.named(name, data_type)[0], node.inputs["Value"])
        self.feed(node.inputs["Index"], index)
        return node.outputs[0]

    def index(self):
        return self.node("GeometryNodeInputIndex").outputs[0]

    def none_differ(self, geometry, domain, differs):
        """True when the boolean field `differs` is False on every element of `domain`.

        The Attribute Statistic of the constant 1 over the elements where `differs` is
        True (its selection): its Max is 1 if there is one, 0 over none. Blender turns
        the selection into an index mask and gathers nothing when no element differs;
        the statistic of `differs` itself would convert it to a float array, copy it and
        scan it (with one pass over the faces, node_fresh: the 35k-vertex triangle mesh's
        topology checks 7.1 -> 4.2 ms at load 3)."""
        stat = self.node("GeometryNodeAttributeStatistic", data_type="FLOAT", domain=domain)
        self.link(geometry, stat.inputs["Geometry"])
        stat.inputs["Attribute"].default_value = 1.0
        self.link(differs, stat.inputs["Selection"])
        return self.compare("FLOAT", "EQUAL", stat.outputs["Max"], 0.0)

    def string_join(self, *parts):
        """The concatenation of `parts` (strings or sockets), in this order."""
        node = self.node("GeometryNodeStringJoin")
        for part in reversed(parts):  # a multi-input lists its last link first
            if isinstance(part, str):
                text = self.node("FunctionNodeInputString", string=part)
                part = text.outputs[0]
            self.link(part, node.inputs["Strings"])
        return node.outputs[0]

    def number_string(self, value):
        node = self.node("FunctionNodeValueToString")
        self.link(value, node.inputs["Value"])
        return node.outputs[0]

    def slice(self, string, start, length):
        node = self.node("FunctionNodeSliceString")
        for sock, value in zip(node.inputs, (string, start, length)):
            self.feed(sock, value)
        return node.outputs[0]

    def switch(self, kind, condition, if_false, if_true):
        """Switch node (lazy: only the chosen input is evaluated)."""
        node = self.node("GeometryNodeSwitch", input_type=kind)
        self.feed(node.inputs["Switch"], condition)
        self.feed(node.inputs["False"], if_false)
        self.feed(node.inputs["True"], if_true)
        return node.outputs[0]

    def index_switch(self, kind, index, values):
        """Index Switch: values[index] (lazy)."""
        node = self.node("GeometryNodeIndexSwitch", data_type=kind)
        while len([s for s in node.inputs if s.identifier.startswith("Item_")]) < len(values):
            node.index_switch_items.new()
        self.feed(node.inputs["Index"], index)
        items = [s for s in node.inputs if s.identifier.startswith("Item_")]
        for sock, value in zip(items, values):
            self.feed(sock, value)
        return node.outputs[0]

    def store(self, geometry, name, data_type, domain, value):
        node = self.node("GeometryNodeStoreNamedAttribute", data_type=data_type, domain=domain)
        self.link(geometry, node.inputs["Geometry"])
        self.feed(node.inputs["Name"], name)
        self.feed(node.inputs["Value"], value)
        return node.outputs[0]

    def repeat(self, iterations, items):
        """A repeat zone: returns (zone_in, zone_out, inner) where ``inner[name]`` is the
        value of state item `name` inside the zone; `items`: [(name, type, start)];
        link the new values into ``zone_out.inputs[name]``; ``zone_out.outputs[name]``
        is the final value."""
        zin = self.node("GeometryNodeRepeatInput")
        zout = self.node("GeometryNodeRepeatOutput")
        zin.pair_with_output(zout)
        zout.repeat_items.clear()
        for name, kind, _ in items:
            zout.repeat_items.new(kind, name)
        self.feed(zin.inputs["Iterations"], iterations)
        for name, _, start in items:
            if start is not None:
                self.feed(zin.inputs[name], start)
        return zin, zout, {name: zin.outputs[name] for name, _, _ in items}

    def warning(self, show, message, kind):
        """A node warning shown while `show` is True; returns `show` passed through it."""
        if not compat.has_node_type(compat.WARNING_NODE):  # Blender 4.2 (see compat)
            return show
        node = self.node(compat.WARNING_NODE, warning_type=kind)
        self.link(show, node.inputs["Show"])
        self.feed(node.inputs["Message"], message)
        return node.outputs["Show"]
