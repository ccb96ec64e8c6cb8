"""The operators' poll checks, each with the sentence Blender shows (and a script's
RuntimeError carries) when it fails: "Operator bpy.ops.object.gerbs_remove.poll() 'Cube'
has no GERBS Blending Surface modifier" instead of "poll() failed, context is incorrect"
(a newcomer's walk, 2026-12-07)."""
from __future__ import annotations

from . import api, ids


def _fail(cls, message: str) -> bool:
    cls.poll_message_set(message)
    return False


def mesh_object(cls, context):
    """The active object if it is a mesh, else None (with the poll message set)."""
    obj = getattr(context, "active_object", None)
    if obj is None:
        return _fail(cls, "No active object") or None
    if obj.type != "MESH":
        return _fail(cls, f"{obj.name!r} is not a mesh") or None
    return obj


def with_surface(cls, context, object_mode: bool = False) -> bool:
    """The active object has the GERBS modifier (and, with `object_mode`, is in Object
    Mode)."""
    obj = mesh_object(cls, context)
    if obj is None:
        return False
    if api.get_modifier(obj) is None:
        return _fail(cls, f"{obj.name!r} has no {ids.MODIFIER_NAME} modifier")
    if object_mode and obj.mode != "OBJECT":
        return _fail(cls, "Only in Object Mode")
    return True
