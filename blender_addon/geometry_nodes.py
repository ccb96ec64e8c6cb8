"""The Geometry Nodes group behind the modifier, and reading/writing its inputs.

Why this route (DESIGN section 7). Blender has no Python API for new modifier
types; a Geometry Nodes modifier is the one modifier Python can define. One
group (built by :mod:`node_tree`) serves every object:

* the settings (kernel, kernel parameters, viewport and render resolution,
  boundary rule, rest shape, normals, memory budget) are group inputs, so they
  live on the modifier (``mod["Socket_N"]``), are animatable and saved in the
  .blend; the add-on's panel draws them (panels.py);
* the surface itself is computed by ``gerbs_core`` and written by the add-on
  into a hidden result object (not linked to any scene; its only user is the
  modifier's hidden "Result" input, so it is saved with the file; a second one,
  "Render Result", at the render resolution). A result mesh also stores the
  input it was built from, what it carries and its settings (snapshot.py); the
  group shows a result only while that record equals what the modifier receives
  now, else the base mesh and a warning (node_tree.py), so a stale surface is
  never shown, applied or exported -- with or without the add-on. The stack,
  visibility toggles, Apply and the glTF/OBJ exporters see an ordinary modifier
  result;
* on an invalid mesh the add-on writes the message into the hidden "Error"
  input: a Warning node shows it in the modifier panel and the base mesh passes
  through unchanged; a build that fails only in a final render goes into "Render
  Error": final renders then show the base mesh (the viewport is not affected).

Alternatives rejected: a Python-only "fake modifier" (an operator rewriting
``obj.data``) destroys the base mesh and breaks Apply/visibility/undo; a
per-object node group with the object baked into an Object Info node works but
multiplies groups and loses the shared settings layout.
"""
from __future__ import annotations

import bpy

from . import ids, node_tree
from . import settings as settings_mod
from .errors import PREFIX


def is_gerbs_group(group) -> bool:
    return group is not None and group.get(ids.GROUP_TAG) is not None


def is_current_group(group) -> bool:
    """The add-on's group of this version, whole: every Group node in it (and in the parts
    it uses) still has its node tree. A user who deletes the hidden ".GERBS" parts (Blender
    File view, or a script) leaves their Group nodes empty and the group would output
    nothing (found by an adversarial test: the object evaluated to 0 vertices, exports
    wrote none, every new surface failed); such a group counts as an old one, so the sync
    moves its modifiers to a rebuilt group (:func:`upgrade_on_sync`)."""
    if not (is_gerbs_group(group) and group.get(ids.GROUP_TAG) == ids.GROUP_VERSION):
        return False
    # walking the nodes costs ~0.5 ms: done again only when the file's node groups change
    # (their session ids: never reused within a session, so a deletion followed by a new
    # group is seen; a count would not see it)
    key = group.session_uid
    groups = tuple(g.session_uid for g in bpy.data.node_groups)
    known = _WHOLE.get(key)
    if known is None or known[0] != groups:
        known = _WHOLE[key] = (groups, _whole(group))
    return known[1]


_WHOLE: dict = {}  # group session id -> (the file's node group session ids, whole)


def _whole(group, seen=None) -> bool:
    seen = set() if seen is None else seen
    for node in group.nodes:
        if node.bl_idname != "GeometryNodeGroup":
            continue
        tree = node.node_tree
        if tree is None:
            return False
        if tree.name not in seen:
            seen.add(tree.name)
            if not _whole(tree, seen):
                return False
    return True


def ensure_group():
    """Return the add-on's node group (this version), creating it if the file has none."""
    for group in bpy.data.node_groups:
        if is_current_group(group):
            return group
    group = bpy.data.node_groups.new(ids.NODE_GROUP_NAME, "GeometryNodeTree")
    group.is_modifier = True
    group[ids.GROUP_TAG] = ids.GROUP_VERSION
    node_tree.build(group)
    return group


def is_gerbs_modifier(mod) -> bool:
    return mod.type == "NODES" and is_gerbs_group(mod.node_group)


def gerbs_modifiers(obj):
    """The object's GERBS modifiers (one is supported; see engine.sync)."""
    if obj is None or obj.type != "MESH":
        return []
    return [m for m in obj.modifiers if is_gerbs_modifier(m)]


def _identifiers(group) -> dict:
    """socket name -> modifier property key ("Socket_N")."""
    return {item.name: item.identifier for item in group.interface.items_tree
            if getattr(item, "in_out", None) == "INPUT"}


def _menu_values(group, spec) -> dict:
    """python value -> stored int of the menu item (the Menu Switch item identifier)."""
    node = group.nodes.get(node_tree.MENU_NODE + spec.key)
    by_label = {s.name: int(s.identifier.split("_")[1])
                for s in node.inputs if s.identifier.startswith("Item_")}
    return {value: by_label[label] for value, label in spec.items.items()}


def _python_value(group, spec, raw):
    """A stored modifier property as the python value the validator checks."""
    if spec.items:
        inverse = {v: k for k, v in _menu_values(group, spec).items()}
        return inverse.get(int(raw), raw)
    if spec.socket_type == "NodeSocketFloat":
        return float(raw) * spec.scale
    if spec.socket_type == "NodeSocketBool":
        return bool(raw)
    return int(raw)


def read_settings(mod) -> dict:
    """The modifier's settings, validated (``settings.validate``: raises
    InvalidParameterError naming a bad value, e.g. one a driver produced)."""
    group = mod.node_group
    keys = _identifiers(group)
    raw = {s.key: _python_value(group, s, mod.get(keys[s.name], s.default))
           for s in ids.SETTINGS if s.name in keys}
    return settings_mod.validate({**ids.DEFAULTS, **raw})


def write_settings(mod, **settings) -> None:
    """Validate `settings` (all of them first: nothing is written if one is bad),
    then store them on the modifier."""
    values = settings_mod.validate(settings)
    group = mod.node_group
    keys = _identifiers(group)
    specs = {s.key: s for s in ids.SETTINGS}
    for key, value in values.items():
        spec = specs[key]
        if spec.items:
            value = _menu_values(group, spec)[value]
        elif spec.socket_type == "NodeSocketFloat":
            value = value / spec.scale
        mod[keys[spec.name]] = value


def property_paths(mod) -> dict:
    """setting key -> the modifier's property path (``'["Socket_N"]'``, for UILayout.prop,
    keyframes and drivers)."""
    keys = _identifiers(mod.node_group)
    return {s.key: f'["{keys[s.name]}"]' for s in ids.SETTINGS if s.name in keys}


def settings_record(settings: dict, resolution: int) -> tuple:
    """The settings a result built with `settings` at `resolution` records
    (``ids.RECORD_SETTINGS`` order; menus as item positions, as the node group sees them)."""
    out = []
    for spec in ids.RECORD_SETTINGS:
        value = resolution if spec.key == "resolution" else settings[spec.key]
        if spec.items:
            value = list(spec.items).index(value)  # the Menu Switch output: item position
        out.append(float(value) / (spec.scale if spec.socket_type == "NodeSocketFloat" else 1))
    return tuple(out)


def _internal(mod, key: str):
    name = next(s.name for s in ids.INTERNAL if s.key == key)
    return _identifiers(mod.node_group)[name]


def get_result(mod, render: bool = False):
    return mod.get(_internal(mod, "render_result" if render else "result"))


def set_result(mod, obj, render: bool = False) -> None:
    mod[_internal(mod, "render_result" if render else "result")] = obj


def get_names(mod) -> str:
    return str(mod.get(_internal(mod, "names"), ""))


def set_names(mod, names: str) -> bool:
    """Store the carried layers' names (the node group slices them). True if changed."""
    key = _internal(mod, "names")
    if str(mod.get(key, "")) == names:
        return False
    mod[key] = names
    return True


def get_error(mod) -> str:
    return str(mod.get(_internal(mod, "error"), ""))


def get_warning(mod) -> str:
    return str(mod.get(_internal(mod, "warning"), ""))


def get_render_error(mod) -> str:
    """The last final render's build error ("" none; also for a group older than v9)."""
    try:
        return str(mod.get(_internal(mod, "render_error"), ""))
    except KeyError:  # an older group, not yet moved to the current one
        return ""


def set_render_error(mod, message: str) -> bool:
    """Make final renders show the input with `message` ("" clears). True if it changed."""
    return set_error(mod, message, "render_error")


def set_warning(mod, message: str) -> bool:
    """Show `message` as the modifier's warning line ("" clears it). True if it changed."""
    return set_error(mod, message, "warning")


def set_error(mod, message: str, socket: str = "error") -> bool:
    """Show `message` as the modifier's error ("" clears it). True if it changed."""
    key = _internal(mod, socket)
    if str(mod.get(key, "")) == message:
        return False
    mod[key] = message
    return True


def upgrade_on_sync(obj, mod) -> str:
    """Move `mod` to the current group when a sync meets an older one (an object appended
    after the file's load: only load, undo and register upgrade; an older group may lack
    the channel's normals, which the sync needs). "" when done or nothing to do (the caller
    re-evaluates); else the error for a modifier that cannot change (a linked object)."""
    if not is_gerbs_group(mod.node_group) or is_current_group(mod.node_group):
        return ""
    if obj.is_editable:
        upgrade(mod)
        return ""
    return (f"{PREFIX}the node group {mod.node_group.name!r} is of an older version of the "
            f"add-on (v{mod.node_group.get(ids.GROUP_TAG)}, this one needs "
            f"v{ids.GROUP_VERSION}) and the object is linked: re-open its file with this "
            f"version, or make the object local")


def upgrade(mod) -> bool:
    """Move a modifier using an older version of the group to the current one,
    keeping its settings (read by socket name) and results; a Render Resolution the
    old group lacks starts at its Resolution (renders look as before). True if it
    changed. Old results carry no current record: the node group shows the base mesh
    until the add-on rebuilds them."""
    old = mod.node_group
    if not is_gerbs_group(old) or is_current_group(old):
        return False
    keys = _identifiers(old)
    raw = {s.key: _python_value(old, s, mod[keys[s.name]])
           for s in ids.SETTINGS if s.name in keys and keys[s.name] in mod}
    if "render_resolution" not in raw and "resolution" in raw:
        raw["render_resolution"] = raw["resolution"]
    kept = {s.key: mod.get(keys[s.name]) for s in ids.INTERNAL
            if s.socket_type == "NodeSocketObject" and s.name in keys}
    mod.node_group = ensure_group()
    for key, value in raw.items():
        try:
            write_settings(mod, **{key: value})
        except ValueError:  # an out-of-range old value: keep the new group's default
            pass
    for key, obj in kept.items():
        if obj is not None:
            set_result(mod, obj, render=key == "render_result")
    return True
