"""The add-on's exceptions and the one-line messages shown in panels and reports.

All derive from gerbs_core's :class:`~gerbs_core.errors.GERBSError`, so one
``except GERBSError`` catches everything the project raises; the ones for bad
input are also ``ValueError`` (like the core's), as before.
"""
from __future__ import annotations

from .core import module as _core_module

_core_errors = _core_module("errors")
GERBSError = _core_errors.GERBSError
GERBSValueError = _core_errors.GERBSValueError
InvalidMeshError = _core_errors.InvalidMeshError
ResourceLimitError = _core_errors.ResourceLimitError

PREFIX = "GERBS: "


class GERBSSyncError(GERBSValueError):
    """The surface could not be built; the message names the problem and indices."""


class NoModifierError(GERBSError, LookupError):
    """The object has no GERBS Blending Surface modifier (or is not a mesh object)."""


class MissingDependencyError(GERBSError, ImportError):
    """The core cannot run in this Blender: scipy is not importable (see core.scipy_problem)."""


class OperationError(GERBSError, RuntimeError):
    """Blender refused an operation (e.g. Apply outside Object Mode or on shared data)."""


def format_error(exc: Exception) -> str:
    """One line naming the problem and where it is (for panels, reports, the log)."""
    if isinstance(exc, InvalidMeshError):
        # the core's text is whole: "<problem>: what is wrong <element words> [indices]";
        # say the tag once and leave the indices where the text names what they count
        text = str(exc).removeprefix(f"{exc.problem}: ")
        return f"{PREFIX}invalid mesh ({exc.problem}): {text}"
    if isinstance(exc, ResourceLimitError):
        return f"{PREFIX}too large: {exc}"
    if isinstance(exc, GERBSError):
        return f"{PREFIX}{exc}"
    # not the user's fault: a defect of gerbs_core (logged with its traceback)
    return f"{PREFIX}internal error in the surface build ({type(exc).__name__}: {exc}); " \
           f"base mesh left as is"


def format_warnings(warnings) -> str:
    """One line summing up the warnings of a build (gerbs_core.mesh.repair.MeshWarning
    records): tag, count and first indices of each repair, the message of a warning that
    names no element; "" when there are none."""
    if not warnings:
        return ""
    plural = {"vertex": "vertices", "face": "faces"}

    def named(w):
        return (f"{len(w.indices)} "
                f"{plural.get(w.element, w.element) if len(w.indices) > 1 else w.element} "
                f"{list(w.indices[:5])}{' ...' if len(w.indices) > 5 else ''}")

    repairs = [w for w in warnings if w.indices and w.tag not in SURFACE_WARNINGS]
    parts = [f"{w.tag} ({named(w)})" for w in repairs]
    # a warning about the surface itself (self_crossing) says what it is, with its faces;
    # one naming no element (fairing_skipped, thin_part) is its own message
    said = (["mesh repaired: " + "; ".join(parts)] if parts else []) + \
        [f"the surface passes through itself at {named(w)} (Select shows them)"
         for w in warnings if w.indices and w.tag in SURFACE_WARNINGS] + \
        [w.message for w in warnings if not w.indices]
    return PREFIX + "; ".join(said)


# warnings about the surface built, not repairs of the mesh (they name input faces)
SURFACE_WARNINGS = ("self_crossing",)


def operator_message(exc: Exception) -> str:
    """The text of an error raised by ``bpy.ops`` (``"Error: ...\\n"``) without the
    prefix Blender adds, so reporting it again does not read "Error: Error: ..."."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    text = "; ".join(line.removeprefix("Error:").strip() for line in lines)
    return text or type(exc).__name__
