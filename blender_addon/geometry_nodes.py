"""The Geometry Nodes group behind the modifier, and reading/writing its inputs.

Why this route (DESIGN section 7). Blender has no Python API for new modifier
types; a Geometry Nodes modifier is the one modifier Python can define. Our
group is::

    Group Input.Result --> Object Info (Original space) --.
                                                          |-- Switch --> Group Output
    Group Input.Geometry ---------------------------------'     ^
    Group Input.Error --> Compare(!= "") --> Warning(Error) ----'

* the settings (kernel, kernel parameters, degree, resolution, face shape,
  boundary rule, normals) are extra group inputs, so they live on the modifier
  (``mod["Socket_N"]``), show in its panel, are animatable and saved in the
  .blend, and one group serves every object;
* the surface itself is computed by ``gerbs_core`` and written by the add-on
  into a hidden result object (not linked to any scene; its only user is the
  modifier's "Result" input, so it is saved with the file and the surface still
  shows when the add-on is missing). Writing new data there re-evaluates the
  modifier; the stack, visibility toggles, Apply, and the glTF/OBJ exporters
  with "apply modifiers" all see an ordinary modifier result;
* on an invalid mesh the add-on writes the message into the hidden "Error"
  input: the Warning node shows it in the modifier panel and the Switch passes
  the base mesh through unchanged.

Alternatives rejected: a Python-only "fake modifier" (an operator rewriting
``obj.data``) destroys the base mesh and breaks Apply/visibility/undo; a
per-object node group with the object baked into an Object Info node works but
multiplies groups and loses the shared settings layout.
"""
from __future__ import annotations

import bpy

from . import ids

_MENU_NODE = "gerbs_menu_"  # name prefix of the Menu Switch nodes defining the menus


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


def _build(group) -> None:
    itf = group.interface
    itf.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    itf.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    sockets = {spec.key: _new_socket(itf, spec) for spec in ids.INTERNAL + ids.SETTINGS}
    nodes, links = group.nodes, group.links
    gin = nodes.new("NodeGroupInput")
    gout = nodes.new("NodeGroupOutput")
    info = nodes.new("GeometryNodeObjectInfo")
    info.transform_space = "ORIGINAL"  # positions are written in the base object's space
    links.new(gin.outputs["Result"], info.inputs["Object"])
    # Menus: a Menu Switch linked to a menu input defines that input's items.
    for k, spec in enumerate(s for s in ids.SETTINGS if s.items):
        menu = nodes.new("GeometryNodeMenuSwitch")
        menu.name = _MENU_NODE + spec.key
        menu.data_type = "INT"
        menu.enum_items.clear()
        for value, label in enumerate(spec.items.values()):
            menu.enum_items.new(label)
        for value, sock in enumerate(s for s in menu.inputs if s.identifier.startswith("Item_")):
            sock.default_value = value
        links.new(gin.outputs[spec.name], menu.inputs["Menu"])
        menu.location = (0, -200 - 150 * k)
        # the items exist once linked: now the default can be set
        sockets[spec.key].default_value = spec.items[spec.default]
    compare = nodes.new("FunctionNodeCompare")
    compare.data_type = "STRING"
    compare.operation = "NOT_EQUAL"
    a_str = next(s for s in compare.inputs if s.identifier == "A_STR")
    links.new(gin.outputs["Error"], a_str)
    warning = nodes.new("GeometryNodeWarning")
    warning.warning_type = "ERROR"
    links.new(compare.outputs[0], warning.inputs["Show"])
    links.new(gin.outputs["Error"], warning.inputs["Message"])
    switch = nodes.new("GeometryNodeSwitch")
    switch.input_type = "GEOMETRY"
    links.new(warning.outputs["Show"], switch.inputs["Switch"])
    links.new(info.outputs["Geometry"], switch.inputs["False"])
    links.new(gin.outputs["Geometry"], switch.inputs["True"])
    links.new(switch.outputs[0], gout.inputs[0])
    gin.location, info.location, switch.location, gout.location = (-400, 0), (-100, 100), (300, 0), (500, 0)
    compare.location, warning.location = (-100, -100), (100, -100)


def is_gerbs_group(group) -> bool:
    return group is not None and group.get(ids.GROUP_TAG) is not None


def ensure_group():
    """Return the add-on's node group, creating it if the file has none."""
    for group in bpy.data.node_groups:
        if is_gerbs_group(group) and group.get(ids.GROUP_TAG) == ids.GROUP_VERSION:
            return group
    group = bpy.data.node_groups.new(ids.NODE_GROUP_NAME, "GeometryNodeTree")
    group.is_modifier = True
    group[ids.GROUP_TAG] = ids.GROUP_VERSION
    _build(group)
    return group


def is_gerbs_modifier(mod) -> bool:
    return mod.type == "NODES" and is_gerbs_group(mod.node_group)


def gerbs_modifiers(obj):
    """The object's GERBS modifiers (usually one)."""
    if obj is None or obj.type != "MESH":
        return []
    return [m for m in obj.modifiers if is_gerbs_modifier(m)]


def _identifiers(group) -> dict:
    """socket name -> modifier property key ("Socket_N")."""
    return {item.name: item.identifier for item in group.interface.items_tree
            if getattr(item, "in_out", None) == "INPUT"}


def _menu_values(group, spec) -> dict:
    """python value -> stored int of the menu item (the Menu Switch item identifier)."""
    node = group.nodes.get(_MENU_NODE + spec.key)
    by_label = {s.name: int(s.identifier.split("_")[1])
                for s in node.inputs if s.identifier.startswith("Item_")}
    return {value: by_label[label] for value, label in spec.items.items()}


def read_settings(mod) -> dict:
    """The modifier's settings as python values (menus as their lower-case keys)."""
    group = mod.node_group
    keys = _identifiers(group)
    out = {}
    for spec in ids.SETTINGS:
        raw = mod.get(keys[spec.name], spec.default)
        if spec.items:
            inverse = {v: k for k, v in _menu_values(group, spec).items()}
            out[spec.key] = inverse.get(int(raw), spec.default)
        elif spec.socket_type == "NodeSocketFloat":
            out[spec.key] = float(raw)
        elif spec.socket_type == "NodeSocketInt":
            out[spec.key] = int(raw)
        else:
            out[spec.key] = bool(raw)
    return out


def write_settings(mod, **settings) -> None:
    """Set settings by keyword; unknown keywords and bad menu values raise ValueError."""
    group = mod.node_group
    keys = _identifiers(group)
    specs = {s.key: s for s in ids.SETTINGS}
    for key, value in settings.items():
        spec = specs.get(key)
        if spec is None:
            raise ValueError(f"unknown GERBS setting {key!r}; expected one of {sorted(specs)}")
        if spec.items:
            values = _menu_values(group, spec)
            # the operators' enums spell items in upper case ("LOGISTIC"): accept both
            value = value.lower() if isinstance(value, str) else value
            if value not in values:
                raise ValueError(f"{key}: expected one of {sorted(values)}, got {value!r}")
            mod[keys[spec.name]] = values[value]
        elif spec.socket_type == "NodeSocketFloat":
            mod[keys[spec.name]] = float(value)
        elif spec.socket_type == "NodeSocketInt":
            mod[keys[spec.name]] = int(value)
        else:
            mod[keys[spec.name]] = bool(value)


def get_result(mod):
    return mod.get(_identifiers(mod.node_group)["Result"])


def set_result(mod, obj) -> None:
    mod[_identifiers(mod.node_group)["Result"]] = obj


def get_error(mod) -> str:
    return str(mod.get(_identifiers(mod.node_group)["Error"], ""))


def set_error(mod, message: str) -> bool:
    """Show `message` as the modifier's error ("" clears it). True if it changed."""
    key = _identifiers(mod.node_group)["Error"]
    if str(mod.get(key, "")) == message:
        return False
    mod[key] = message
    return True
