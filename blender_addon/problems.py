"""What the panel says about the modifier, in a modeller's words (no bpy drawing here).

:func:`headline` turns a core error into one short sentence (the full message stays
on the modifier and in the log); :func:`stack_notes` says which modifiers around
GERBS cannot be honoured and why; :func:`wrap` cuts text to a panel's width;
:func:`selection` gives the elements of the base mesh the select operator selects.
"""
from __future__ import annotations

import textwrap

import bpy

from . import finite, ids, mesh_io
from .errors import PREFIX

_PLAIN = {
    "non_manifold_edge": "{n} edge{s} shared by more than two faces",
    "inconsistent_orientation": "faces on {n} edge{s} face opposite ways (flipped normals: "
                                "Mesh > Normals > Recalculate Outside)",
    "non_manifold_vertex": "{n} vertex{es} where separate fans of faces touch (bow-tie)",
    "unused_vertex": "{n} vertex{es} in no face (loose)",
    "degenerate_face": "{n} face{s} with no area or fewer than three corners",
    "repeated_index": "{n} face{s} that visit a vertex twice",
    "duplicate_face": "{n} face{s} on top of another with the same vertices",
    "index_out_of_range": "{n} face{s} that name vertices the mesh does not have",
    "non_finite": "{n} vertex{es} with an invalid (NaN or infinite) coordinate",
    "outlier_vertex": "{n} stray vertex{es} far away from the rest",
    "zero_length_edge": "{n} edge{s} of zero length (merge by distance)",
    "empty": "no faces",
    "non_finite_attribute": "a NaN or infinite value in {layer} at {n} {elements}",
}


def headline(message: str, problem=None) -> str:
    """One sentence for the panel: what is wrong, in plain words."""
    if getattr(problem, "problem", None) == "empty" and "degenerate" in message:
        # faces there are, but none with an area (the repair's own words, not "no faces")
        return "Every face of the mesh is degenerate: none has three distinct corners and an area."
    if problem is not None and getattr(problem, "problem", None) in _PLAIN:
        count = len(problem.edges) if getattr(problem, "edges", None) else \
            len(problem.indices) or 1
        one = count == 1
        element = getattr(problem, "element", "")
        text = _PLAIN[problem.problem].format(
            n=count, s="" if one else "s", es="" if one else "es",
            layer=f'"{getattr(problem, "layer", "")}"',
            elements=element if one or not element else finite.plural(element))
        return f"The mesh has {text}."
    text = message.removeprefix(PREFIX)
    return text[:1].upper() + text[1:]


def wrap(text: str, width_px: float, scale: float = 1.0) -> list:
    """`text` in lines that fit a panel `width_px` wide at UI `scale` (about 7 px a
    character at scale 1; at least 20 characters a line)."""
    chars = max(20, int(width_px / (7.0 * max(scale, 0.1))) - 4)
    return textwrap.wrap(text, chars) or [""]


def selection(problem) -> dict:
    """{"vertex": [...], "edge": [(a, b), ...], "face": [...]} of an InvalidMeshError."""
    out = {"vertex": [], "edge": [], "face": []}
    if problem is None:
        return out
    edges = getattr(problem, "edges", None)
    if edges:
        out["edge"] = [tuple(int(i) for i in e) for e in edges]
    elif problem.element in out and problem.indices:
        out[problem.element] = [int(i) for i in problem.indices]
    elif getattr(problem, "faces", None):  # e.g. the faces of corners (finite.non_finite)
        out["face"] = [int(i) for i in problem.faces]
    return out


def _renders_differently(m) -> str:
    if m.show_render != m.show_viewport:
        return f"{m.name} is on only in {'renders' if m.show_render else 'the viewport'}"
    if m.type in ("SUBSURF", "MULTIRES") and getattr(m, "levels", 0) != getattr(
            m, "render_levels", getattr(m, "levels", 0)):
        return f"{m.name} has other levels in renders"
    return ""


def stack_notes(obj, mod, background: bool, locked: bool, settings: dict) -> list:
    """Plain sentences about the stack: what a render or the stack does differently."""
    mods = list(obj.modifiers)
    above = mods[:mods.index(mod)]
    notes = []
    scene = getattr(bpy.context, "scene", None)  # the panel's scene (the one being shown)
    props = getattr(scene, ids.SCENE_PROP, None)
    if props is not None and not props.live_update:
        notes.append("Live Update is off (Scene): edits are not followed; an edited mesh "
                     "shows its base mesh until Rebuild or Live Update is on again.")
    differs = [t for t in (_renders_differently(m) for m in above) if t]
    if differs and not (background or locked):
        notes.append(f"{'; '.join(differs)}: renders show the base mesh unless "
                     f"Render > Lock Interface is on (GERBS then builds the render surface).")
    elif (settings.get("render_resolution") != settings.get("resolution")
          and not (background or locked)):
        notes.append("Renders use the viewport resolution unless Render > Lock Interface "
                     "is on (GERBS then builds the render resolution).")
    return notes


def on_base_mesh(obj, mod) -> bool:
    """Do the indices of a build's problem name elements of the base mesh (no enabled
    modifier above GERBS makes the mesh it receives)?"""
    mods = list(obj.modifiers)
    edit = mesh_io.editing(obj)
    return not any(m.show_viewport and (not edit or m.show_in_editmode)
                   for m in mods[:mods.index(mod)])
