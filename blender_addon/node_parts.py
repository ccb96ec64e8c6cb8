"""Small node groups (*parts*) the add-on's group instances, each built once per file.

Blender builds a node tree in time quadratic in its node count, so the checks that
repeat (one per carried layer type and domain, one per result) live in small groups
of their own, each used through one Group node. A part carries its key
(``ids.PART_TAG``) and the group version (``ids.PART_VERSION``): a file keeps the
parts of this version and builds the missing ones; older ones go with the groups
that used them (:func:`collect_unused`). Names start with "." (hidden in Blender's
node group lists).
"""
from __future__ import annotations

import bpy

from . import ids
from .node_helpers import Tree


def is_part(group) -> bool:
    return group is not None and group.get(ids.PART_TAG) is not None


def ensure(key: str, inputs, outputs, build):
    """The part `key` of this version, built if the file has none.

    `inputs`, `outputs`: [(name, socket type)] of its interface; ``build(t, gin, gout)``
    fills it (`gin`: the Group Input's outputs, `gout`: the Group Output's inputs)."""
    for group in bpy.data.node_groups:
        if group.get(ids.PART_TAG) == key and group.get(ids.PART_VERSION) == ids.GROUP_VERSION:
            return group
    group = bpy.data.node_groups.new(ids.PART_PREFIX + key, "GeometryNodeTree")
    try:
        for in_out, sockets in (("OUTPUT", outputs), ("INPUT", inputs)):
            for name, kind in sockets:
                group.interface.new_socket(name, in_out=in_out, socket_type=kind)
        t = Tree(group)
        gin, gout = t.node("NodeGroupInput"), t.node("NodeGroupOutput")
        build(t, gin.outputs, gout.inputs)
    except Exception:  # a half-built part must not be found by the next ensure
        bpy.data.node_groups.remove(group)
        raise
    group[ids.PART_TAG], group[ids.PART_VERSION] = key, ids.GROUP_VERSION
    return group


def collect_unused() -> int:
    """Delete the parts nothing uses (a part freed by another's removal included)."""
    removed = 0
    while True:
        unused = [g for g in bpy.data.node_groups if is_part(g) and g.users == 0]
        if not unused:
            return removed
        for group in unused:
            bpy.data.node_groups.remove(group)
        removed += len(unused)
