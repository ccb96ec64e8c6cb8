"""What differs between the Blender versions the add-on supports (4.2 LTS .. newest).

Every version test lives here, so the rest of the add-on asks for a feature,
not for a version number:

* the Geometry Nodes *Warning* node exists from Blender 4.3 on; on 4.2 the
  node group is built without it, and a modifier's error shows in the GERBS
  panel, the status bar and the log instead of on the modifier itself;
* in the ``bpy`` module (Blender as a Python module, ``bpy.app.binary_path`` is
  empty) nothing disables add-ons at exit: Blender's own exit path does that only
  in the application. A class or handler that is still registered when Python
  exits makes bpy 4.2 crash (SIGSEGV) and bpy 4.5 report thousands of unfreed
  memory blocks and hang, so :func:`at_exit` tells whether the add-on must
  unregister itself from an ``atexit`` hook.
"""
from __future__ import annotations

import bpy

WARNING_NODE = "GeometryNodeWarning"


def has_node_type(kind: str) -> bool:
    """Is the node type `kind` (e.g. "GeometryNodeWarning") known to this Blender?

    Asked before creating a node: ``nodes.new`` of an unknown type prints an
    error to stderr even when the RuntimeError is caught."""
    return hasattr(bpy.types, kind)


def at_exit() -> bool:
    """Must the add-on unregister itself when Python exits (the ``bpy`` module)?"""
    return not bpy.app.binary_path


def limitations() -> list[str]:
    """One sentence per feature this Blender lacks (empty on Blender 4.3+)."""
    out = []
    if not has_node_type(WARNING_NODE):
        version = ".".join(map(str, bpy.app.version[:2]))
        out.append(f"Blender {version} has no Geometry Nodes Warning node (4.3+): GERBS errors "
                   f"show in the GERBS panel and the status bar, not on the modifier")
    return out
