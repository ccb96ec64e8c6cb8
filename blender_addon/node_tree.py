"""Building the node group behind the modifier (see geometry_nodes.py for why).

The group shows a hidden result object only while that result is *fresh*
(node_fresh.py): built from exactly the geometry the modifier receives now, with
exactly what it carries and the current settings. There are two results: "Result"
at the viewport resolution (viewport, Apply, exports) and "Render Result" at the
render resolution (final renders)::

    view   = Result if no Error and Result is fresh for Resolution
             else the input, passed on with the channel (node_fresh.channel)
    render = the input, passed on with the channel, if Render Error (the last final
             render's build failed: it shows the modifier's input, as a failed build
             does in the viewport, never a surface of another resolution)
             else Render Result if no Error and it is fresh for Render Resolution
             else view (a render without its own result shows the viewport surface)
    output = view in the viewport (Is Viewport), render in final renders,
             results with their vertex groups written and without their record

The comparisons are exact (epsilon 0): the add-on stores the float32 values it
read, so any edit, however small, makes the result stale. This is what keeps a
stale surface from being shown, applied or exported when nothing updated the
result: a file opened without the add-on, a frame change the add-on missed,
``modifier_apply`` right after an edit. With the add-on running, the handlers
rebuild the result within the same depsgraph update and the second evaluation
shows it. Switch nodes are lazy, so the viewport never reads the render result.

The checks and the shown result are nested groups (node_parts.py, built by
node_fresh.py), one Group node each here: Blender builds a tree in time quadratic
in its node count, and each check is used twice (viewport and render result).

Every setting is hidden in the modifier's own input list: the add-on's panel
draws them (only the chosen kernel's parameters), panels.py.
"""
from __future__ import annotations

from . import ids, node_fresh
from .node_helpers import Tree

MENU_NODE = "gerbs_menu_"  # name prefix of the Menu Switch nodes defining the menus


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
    sock.hide_in_modifier = True  # internal state, or drawn by the add-on's panel
    return sock


def _menus(t: Tree, gin, sockets) -> dict:
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


def _fresh(t: Tree, gin, base, result, current, resolution):
    return node_fresh.fresh(t, base, result, gin.outputs["Attribute Names"], current, resolution)


def _shown(t: Tree, gin, result):
    """A result as shown: its weights in its vertex groups, its record removed."""
    return node_fresh.shown(t, result, gin.outputs["Attribute Names"])


def build(group) -> None:
    """Fill an empty Geometry Nodes group with the interface and the tree above."""
    itf = group.interface
    itf.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    itf.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    sockets = {spec.key: _new_socket(itf, spec) for spec in ids.INTERNAL + ids.SETTINGS}
    t = Tree(group)
    gin, gout = t.node("NodeGroupInput"), t.node("NodeGroupOutput")
    base = gin.outputs["Geometry"]
    current = {spec.key: gin.outputs[spec.name] for spec in ids.SETTINGS}
    current.update(_menus(t, gin, sockets))
    results = {}
    for key in ("result", "render_result"):  # Object Info in the base object's space
        info = t.node("GeometryNodeObjectInfo", transform_space="ORIGINAL")
        t.link(gin.outputs[[s.name for s in ids.INTERNAL if s.key == key][0]],
               info.inputs["Object"])
        results[key] = info.outputs["Geometry"]
    has_error = t.warning(t.compare("STRING", "NOT_EQUAL", gin.outputs["Error"], ""),
                          gin.outputs["Error"], "ERROR")
    no_error = t.boolean("NOT", has_error)
    view_fresh, view_kept = _fresh(t, gin, base, results["result"], current,
                                   current["resolution"])
    stale = t.warning(t.boolean("AND", no_error, t.boolean("NOT", view_fresh)),
                      ids.STALE_MESSAGE, "WARNING")
    repaired = t.warning(t.boolean("AND", no_error, view_fresh, t.compare(
        "STRING", "NOT_EQUAL", gin.outputs["Warning"], "")), gin.outputs["Warning"], "WARNING")
    used = t.boolean("OR", repaired, t.boolean("NOT", repaired))  # (evaluates the warning)
    passed = node_fresh.channel(t, base, results["result"], gin.outputs["Attribute Names"],
                                view_kept, current["use_normals"])
    view = t.switch("GEOMETRY", t.boolean("AND", no_error, t.boolean("NOT", stale), used),
                    passed, _shown(t, gin, results["result"]))
    render_fresh = _fresh(t, gin, base, results["render_result"], current,
                          current["render_resolution"])[0]
    render = t.switch("GEOMETRY", t.boolean("AND", no_error, render_fresh), view,
                      _shown(t, gin, results["render_result"]))
    render = t.switch("GEOMETRY", t.compare("STRING", "NOT_EQUAL", gin.outputs["Render Error"],
                                            ""), render, passed)
    is_viewport = t.node("GeometryNodeIsViewport").outputs[0]
    t.link(t.switch("GEOMETRY", is_viewport, render, view), gout.inputs[0])
    gin.location, gout.location = (-900, 0), (1400, 0)
