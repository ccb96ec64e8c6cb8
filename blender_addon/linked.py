"""Objects linked from a library (File > Link, a linked collection instance,
``bpy.data.libraries.load(link=True)``): read-only.

Python may write a linked object's modifier, its result object and mesh (Blender does
not stop it), but such writes change the library's data in this session only, are lost
on save and can show a surface the library file does not have. So the add-on never
writes them: no build, no record, no error line on the modifier, no node group upgrade.
The node group itself still decides what shows (node_tree.py): the surface saved in
the library while its record equals what the modifier receives, else the base mesh.
The sync only looks (:func:`check`, reading evaluated data) and says why when the base
mesh shows: that message goes into the state (``api.status``, the panel), the status
bar and the log, never into the linked modifier.

A library override is local data (its modifier may be written and is saved with the
file): it syncs like any local object, with a result of its own where the one it points
at is still the library's (results.is_own).
"""
from __future__ import annotations

from .errors import PREFIX


def is_linked(obj) -> bool:
    """Is `obj` library data (read-only to the add-on)? Overrides are local: False."""
    return obj is not None and obj.library is not None


def library_name(obj) -> str:
    library = obj.library
    return library.filepath or library.name


def refusal(obj, what: str) -> str:
    """The message of a change the add-on refuses on a linked object (api)."""
    return (f"{obj.name!r} is linked from the library {library_name(obj)!r} and read-only: "
            f"{what} it in the library file, or make the object local or a library "
            f"override first")


def stale_message(obj) -> str:
    return (f"{PREFIX}{obj.name!r} is linked from the library {library_name(obj)!r}, whose "
            f"saved surface does not match this mesh or its settings, so the base mesh is "
            f"shown; the add-on does not change library data: rebuild it in the library "
            f"file (open it with the add-on), or make the object local or a library "
            f"override")


def check(obj, mod, depsgraph, use_normals: bool) -> str:
    """"" while the linked `obj`'s modifier shows its saved surface (or is not evaluated
    here, or a modifier below it that changes the mesh hides what it shows), else why it
    shows the base mesh. Reads evaluated data only; writes nothing."""
    from . import stack

    inp, problem, _ = stack.read_input(obj, mod, depsgraph, use_normals)
    if problem:
        return problem
    if inp is None or inp is stack.FRESH:
        return ""
    if not stack.stack_of(obj, mod, depsgraph.mode == "RENDER").deform_after:
        return ""  # read from the mesh data-block: the final mesh cannot say what shows
    return stale_message(obj)
