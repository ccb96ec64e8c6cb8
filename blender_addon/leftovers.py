"""What Blender's own Apply leaves of a GERBS modifier that passed its input on.

While the node group shows no surface (an invalid mesh, Live Update off after an edit)
it passes the input on with the *channel* (``ids.CHANNEL_PREFIX`` attributes:
node_fresh.channel), which the add-on reads from the final mesh. Blender's Apply (the
modifier panel, ``bpy.ops.object.modifier_apply``) and Convert to Mesh bake that output
into the user's mesh, channel included, and nothing in the node tree can tell an Apply
from an evaluation. So once the add-on sees a modifier it synced gone (handlers: the
next depsgraph update, at once in the interface; in a script at its next evaluation,
e.g. ``view_layer.update()``), it removes the channel attributes from that object's
mesh: the mesh comes back as it was. ``api.apply`` never leaves them (it applies a fresh
surface only). Only the add-on's own hidden names are touched, never the positions; not
in Edit Mode (the edit BMesh would write them back), not in a mesh another object uses
or a library's.
"""
from __future__ import annotations

import logging

import bpy

from . import ids
from . import geometry_nodes as gn

log = logging.getLogger(__name__)


def remove_channels(uids) -> int:
    """Remove the channel attributes from the meshes of the objects whose session uids are
    in `uids` and that have no GERBS modifier any more. Returns the number removed."""
    if not uids:
        return 0
    removed = 0
    for obj in bpy.data.objects:
        if obj.session_uid not in uids or obj.type != "MESH" or gn.gerbs_modifiers(obj):
            continue
        mesh = obj.data
        if (mesh is None or mesh.is_editmode or mesh.users > 1 or obj.library is not None
                or mesh.library is not None):
            continue
        names = [a.name for a in mesh.attributes if a.name.startswith(ids.CHANNEL_PREFIX)]
        for name in names:
            mesh.attributes.remove(mesh.attributes[name])
        if names:
            log.debug("GERBS: %s: removed %s (left by applying the modifier)", obj.name, names)
            mesh.update()
        removed += len(names)
    return removed
