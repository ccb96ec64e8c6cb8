#!/usr/bin/env python
"""Main job: a GERBS blending surface of a mesh file, headless, through Blender.

    .venv/bin/python scripts/gerbs_surface.py        # bundled sample -> out/suzanne_gerbs.glb
    .venv/bin/python scripts/gerbs_surface.py examples/suzanne.obj -o out.glb
    .venv/bin/python scripts/gerbs_surface.py in.ply -o out.obj --resolution 6

Reads OBJ, glTF (.gltf/.glb), PLY or STL with Blender's own importers, adds the
GERBS Blending Surface modifier to every imported mesh (``blender_addon.api``),
and writes OBJ or glTF (by the output extension) with Blender's exporters,
modifiers applied. What reaches the surface is the mesh as stored; see
:func:`import_mesh` for what each importer does and ``--merge-distance``.

Creases: the modifier uses Blender's ``crease_edge`` / ``crease_vert`` attributes.
Of the input formats only PLY brings creases along (Blender's PLY exporter and importer
carry point attributes: ``crease_vert``; no format carries edge creases), so
``--crease-angle DEG`` creases the edges sharper than DEG degrees and
``--sharp-creases`` those the importer marks sharp (:func:`mark_creases`).

Safety: paths are checked before anything is read (the output may not be the
input, a directory, or below a file; a glTF input may only reference files in
its own folder), the result is exported into a temporary folder beside the
output and renamed into place (a .gltf and its .bin side by side), and no
output file may replace a file the input uses; the output's folder must exist (only
the default ``out/`` is made). Every problem the user can cause
ends in one ``error: ...`` line on stderr and exit status 2 with nothing written
(the input is never written).
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shutil
import struct
import sys
import tempfile
import urllib.parse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "examples" / "suzanne.obj"
INPUTS = (".obj", ".gltf", ".glb", ".ply", ".stl")
OUTPUTS = (".obj", ".gltf", ".glb")
USER_ERROR = 2


class UserError(Exception):
    """A problem with the command line or the files: one line, exit status 2."""


def cli_words(text: str) -> str:
    """A core or add-on message in the command line's words: the settings that have an
    option here are named by it (``merge_distance`` -> ``--merge-distance``)."""
    for name in ("merge_distance", "memory_budget"):
        text = re.sub(rf"(?<![-\w]){name}\b", "--" + name.replace("_", "-"), text)
    return text


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line instead of usage + message
        raise UserError(message)


def kernel_options() -> dict:
    """{setting key: (kernel label, its SocketSpec)} of every kernel parameter, from the
    core's one table of kernels (through the add-on's settings): the ``--alpha`` ...
    ``--bfbs-right`` options."""
    from blender_addon import ids

    specs = {s.key: s for s in ids.SETTINGS}
    return {key: (ids.KERNELS[name], specs[key])
            for name, keys in ids.KERNEL_PARAMETERS.items() for key in keys}


def parse_args(argv):
    from blender_addon import ids
    from gerbs_core.kernels import KERNELS

    p = _Parser(description="GERBS blending surface of a mesh file (headless Blender)")
    p.add_argument("input", nargs="?", type=Path, default=SAMPLE,
                   help=f"mesh file {INPUTS} (default: the bundled {SAMPLE.relative_to(ROOT)})")
    p.add_argument("-o", "--output", type=Path, default=None,
                   help=f"output {OUTPUTS}, in an existing folder (default: "
                        "out/<input name>_gerbs.glb under the current directory, out/ made "
                        "if need be)")
    p.add_argument("--resolution", type=int, default=4,
                   help="segments per mesh edge, 1..64 (default 4)")
    p.add_argument("--kernel", default="erbs", choices=list(KERNELS),
                   help="how each vertex's patch blends into its neighbours (default erbs)")
    p.add_argument("--boundary", default="keep", choices=list(ids.BOUNDARIES),
                   help="open borders: keep (border vertices keep their corners; a flat "
                        "mesh stays flat) or straighten (the border runs smoothly through "
                        "its vertices, corners rounded) (default keep)")
    p.add_argument("--shading", default="smooth", choices=("smooth", "keep"),
                   help="smooth: every output face smooth shaded and no edge sharp but "
                        "the fully creased ones (the surface is smooth; what a viewer shows "
                        "then follows its vertex normals); keep: each "
                        "output face shaded like the input face it lies in, as the modifier "
                        "does in Blender (an OBJ with 's 0' and no normals, like the bundled "
                        "sample: flat, faceted; Blender's OBJ importer shades every face of "
                        "a file with vertex normals smooth, its flat look lying in split "
                        "normals, which the surface does not carry) (default smooth)")
    for key, (label, spec) in kernel_options().items():
        integer = spec.socket_type == "NodeSocketInt"
        p.add_argument(f"--{key.replace('_', '-')}", type=int if integer else float,
                       default=None, help=f"{label} parameter {spec.name!r}, {spec.min:g}.."
                                          f"{spec.max:g} (default {spec.default:g})")
    p.add_argument("--memory-budget", type=float, default=None, metavar="MB",
                   help="largest memory the output (stencil or tessellation) may use, in "
                        "MB; the construction before it may use the larger of this and "
                        "2000 MB (default 2000)")
    p.add_argument("--merge-distance", type=float, default=None, metavar="D",
                   help="weld vertices closer than D (0: only coincident ones) before "
                        "building, e.g. seams split by an exporter; off by default")
    p.add_argument("--crease-angle", type=float, default=None, metavar="DEG",
                   help="fully crease the edges whose faces meet at more than DEG degrees "
                        "(angle between their normals, 0..180): sharp mesh edges stay sharp")
    p.add_argument("--sharp-creases", action="store_true",
                   help="fully crease the edges the importer marks sharp (OBJ smoothing "
                        "groups) or whose faces' normals differ at a shared corner (glTF "
                        "split normals; with --merge-distance, which welds the seams "
                        "first)")
    p.add_argument("--up-axis", choices=("Y", "Z"), default=None,
                   help="the up axis of an OBJ, PLY or STL input: Y (OBJ's usual) or Z (CAD, "
                        "3D printing); an OBJ output is written the same way, a glTF one "
                        "Y-up as its format says (default: each importer's own, Y for OBJ, "
                        "Z for PLY and STL)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    if args.up_axis is not None and args.input.suffix.lower() in (".gltf", ".glb"):
        raise UserError("--up-axis: a glTF input is Y-up by its format; the option is for "
                        "OBJ, PLY and STL inputs")
    args.default_output = args.output is None  # only the default's folder is made
    if args.default_output:
        args.output = Path("out") / f"{args.input.stem}_gerbs.glb"
    if args.merge_distance is not None and not args.merge_distance >= 0:  # (also NaN)
        raise UserError(f"--merge-distance: must be >= 0, got {args.merge_distance}")
    if args.crease_angle is not None and not 0 <= args.crease_angle <= 180:  # (also NaN)
        raise UserError(f"--crease-angle: must be in [0, 180] degrees, got {args.crease_angle}")
    return args


def settings_from(args) -> dict:
    """The surface settings, checked by the add-on's one validator."""
    from blender_addon import settings as settings_mod

    values = dict(resolution=args.resolution, kernel=args.kernel, boundary=args.boundary)
    for name in kernel_options():
        if getattr(args, name) is not None:
            values[name] = getattr(args, name)
    if args.merge_distance is not None:  # the core's merge by distance (settings "merge")
        values.update(merge=True, merge_distance=args.merge_distance)
    if args.memory_budget is not None:
        if not 1.0 <= args.memory_budget <= 1.0e6:  # (also NaN)
            raise UserError(f"--memory-budget: must be in [1, 1e+06] MB, got {args.memory_budget}")
        values["memory_budget"] = args.memory_budget * 1e6
    try:
        return settings_mod.validate(values)
    except ValueError as exc:  # InvalidParameterError "name: message"
        name = getattr(exc, "name", "")
        raise UserError(f"--{name.replace('_', '-')}{str(exc)[len(name):]}") from None


# --- paths ----------------------------------------------------------------------

def _absolute(path: Path) -> Path:
    return Path(os.path.abspath(path))


def _same_file(a: Path, b: Path) -> bool:
    if a.resolve() == b.resolve():
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_paths(args) -> tuple[Path, Path]:
    """(input, output) as absolute paths; refuses what would read or write the wrong file."""
    src, out = _absolute(args.input), _absolute(args.output)
    if src.suffix.lower() not in INPUTS:
        raise UserError(f"input must be one of {', '.join(INPUTS)}, got {args.input.name}")
    if out.is_dir():  # before the suffix: "-o ." named no file at all
        raise UserError(f"output {args.output} is a directory; give a file name")
    if out.suffix.lower() not in OUTPUTS:
        raise UserError(f"output must be one of {', '.join(OUTPUTS)}, got {args.output.name}")
    if not src.exists():
        raise UserError(f"input file {args.input} does not exist")
    if not src.is_file():
        raise UserError(f"input {args.input} is not a file")
    if src.stat().st_size == 0:
        raise UserError(f"input file {args.input} is empty")
    if _same_file(src, out):
        raise UserError(f"output {args.output} is the input file; choose another name")
    ancestor = out.parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UserError(f"cannot write {args.output}: {ancestor} is not a directory")
    if ancestor != out.parent and not args.default_output:  # a typo is not a request to mkdir
        raise UserError(f"cannot write {args.output}: its folder {args.output.parent} does "
                        f"not exist; create it first")
    return src, out


def _gltf_document(path: Path) -> dict:
    data = path.read_bytes()
    if path.suffix.lower() == ".glb":
        if len(data) < 20 or data[:4] != b"glTF":
            raise UserError(f"{path.name} is not a binary glTF (.glb) file")
        version, length = struct.unpack_from("<II", data, 4)
        chunk_length, chunk_type = struct.unpack_from("<I4s", data, 12)
        if version != 2 or chunk_type != b"JSON" or 20 + chunk_length > min(length, len(data)):
            raise UserError(f"{path.name} is not a glTF 2.0 binary file (bad header)")
        data = data[20:20 + chunk_length]
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        raise UserError(f"{path.name} is not a glTF file (its JSON cannot be read)") from None
    if not isinstance(doc, dict):
        raise UserError(f"{path.name} is not a glTF file (no JSON object)")
    return doc


def gltf_references(path: Path) -> list[Path]:
    """The files a glTF input reads (buffers and images), all inside its folder."""
    folder = path.parent.resolve()
    refs = []
    doc = _gltf_document(path)
    for kind in ("buffers", "images"):
        items = doc.get(kind) or []
        for i, item in enumerate(items if isinstance(items, list) else []):
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:"):
                continue
            parts = urllib.parse.urlsplit(uri)
            target = (folder / urllib.parse.unquote(parts.path)).resolve()
            if parts.scheme or parts.netloc or not target.is_relative_to(folder):
                raise UserError(f"{path.name}: {kind}[{i}] refers to {uri!r}, outside the "
                                f"input's folder; refusing to read it")
            refs.append(target)
    return refs


def obj_references(path: Path) -> list[Path]:
    """The material libraries an OBJ input names (``mtllib``, relative to its folder), so
    that an OBJ output's own .mtl never replaces one of them."""
    refs = []
    try:
        with open(path, "rb") as f:
            for line in f:
                line = line.lstrip()
                if line.startswith(b"mtllib"):
                    name = line[6:].strip().decode("utf-8", "replace")
                    if name:
                        refs.append((path.parent / name).resolve())
    except OSError:
        pass  # unreadable: the importer says so
    return refs


# --- import ---------------------------------------------------------------------

def import_mesh(bpy, path: Path, up=None):
    """Import with Blender's importer; return the new mesh objects.

    What reaches the surface: OBJ, PLY and glTF faces exactly as indexed in the
    file (glTF exporters split vertices where normals or UVs differ, a PLY
    exported with UVs is split at UV seams: the surface then has open seams
    there, named in a warning, unless ``--merge-distance`` is given); STL has no
    connectivity: Blender's importer joins corners at identical positions. Loose
    vertices are ignored, bow-ties (e.g. where joining by position makes two
    fans meet) and non-manifold edges are split by the core's repair
    (gerbs_core.mesh.repair), which also does the merge by distance.
    """
    before = set(bpy.data.objects)
    ext = path.suffix.lower()
    if ext == ".obj":
        check_obj_numbers(path)
    try:
        # the glTF importer logs its progress on standard output: not ours to show
        with _stdout_silenced():
            _import(bpy, ext, path, up)
    except RuntimeError as exc:
        from blender_addon.errors import operator_message
        raise UserError(f"cannot read {path.name}: {operator_message(exc)}") from None
    # the meshes of the file: not the bone shapes the glTF importer adds, hidden, in its
    # "glTF_not_exported" collection (an export test: a surface was built for them)
    return [o for o in bpy.data.objects if o not in before and o.type == "MESH"
            and o.visible_get()]


# a vertex line with a word that may not be a finite single-precision number: nan, inf,
# or an exponent of 38 or more (a review: "1e39" and "1e999" also read as 0)
_SUSPECT = re.compile(rb"(?im)^[ \t]*v[ \t][^\n]*?(nan|inf|e\+?0*(3[89]|[4-9]\d|\d{3,}))")
_FLOAT32_MAX = 3.4028234663852886e38


def check_obj_numbers(path: Path) -> None:
    """Refuse an OBJ whose vertex lines hold a coordinate that is not a finite single-
    precision number (NaN, infinite, beyond 3.4e38): Blender's OBJ importer reads them as 0
    (found by a test with messy meshes: a dented surface, exit 0, no word). A regular
    expression over the vertex lines first: most files have none."""
    data = path.read_bytes()
    if not _SUSPECT.search(data):
        return
    bad = []
    for number, line in enumerate(data.splitlines(), 1):
        words = line.split()
        if words[:1] != [b"v"]:
            continue
        try:
            xyz = [float(w) for w in words[1:4]]
        except ValueError:
            continue  # the importer's to judge
        if not all(abs(c) <= _FLOAT32_MAX for c in xyz):  # (False for NaN too)
            bad.append(number)
    if bad:
        lines = ", ".join(map(str, bad[:5])) + (" ..." if len(bad) > 5 else "")
        raise UserError(f"{path.name}: NaN, infinite or out-of-range (beyond 3.4e38) vertex "
                        f"coordinates on line(s) {lines} ({len(bad)} vertices): Blender's OBJ "
                        f"importer would read them as 0; fix those vertices")


def obj_rounding(bpy, objects) -> str:
    """A warning when Blender's OBJ exporter, which writes 6 decimals (up to 5e-7 off per
    coordinate), moves the output's points by more than 0.1% of its median edge (found by
    a test with messy meshes: Suzanne at 0.27 mm came back folded), else ''."""
    import numpy as np

    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in objects:
        mesh = obj.evaluated_get(depsgraph).data
        P = _get(mesh.vertices, "co", len(mesh.vertices), np.float32, 3).astype(np.float64)
        M = np.array(obj.matrix_world)  # the exporter writes world coordinates (a review:
        P = P @ M[:3, :3].T + M[:3, 3]  # a glTF node scaled by 1e-4 went unwarned)
        E = _get(mesh.edges, "vertices", len(mesh.edges), np.int32, 2)
        if not len(E):
            continue
        edge = float(np.median(np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1)))
        if 0.5e-6 * 3 ** 0.5 > 1e-3 * edge:
            return (f"{obj.name}: OBJ stores 6 decimals, and the output's edges (median "
                    f"{edge:.2g}) are so short that the rounding moves points by up to "
                    f"{0.5e-6 * 3 ** 0.5 / edge:.1%} of an edge; write .glb, or scale the model up")
    return ""


def axes(up: str | None) -> dict:
    """The importers' and the OBJ exporter's axis keywords for ``--up-axis`` (none: each
    one's default)."""
    if up is None:
        return {}
    return {"Y": {"forward_axis": "NEGATIVE_Z", "up_axis": "Y"},
            "Z": {"forward_axis": "Y", "up_axis": "Z"}}[up]


def _import(bpy, ext: str, path: Path, up=None) -> None:
    if ext == ".obj":
        bpy.ops.wm.obj_import(filepath=str(path), **axes(up))
    elif ext in (".gltf", ".glb"):
        bpy.ops.import_scene.gltf(filepath=str(path), merge_vertices=False)
    elif ext == ".ply":
        bpy.ops.wm.ply_import(filepath=str(path), **axes(up))
    else:
        bpy.ops.wm.stl_import(filepath=str(path), **axes(up))


# --- creases --------------------------------------------------------------------

def _get(collection, name, n, dtype, width=1):
    import numpy as np
    buf = np.empty(n * width, dtype=dtype)
    collection.foreach_get(name, buf)
    return buf.reshape(-1, width) if width > 1 else buf


def _corners(mesh):
    """(face (C,), edge (C,), loop_start (F,), loop_total (F,)) of the corners of `mesh`:
    each corner's face and the edge from it to the face's next corner."""
    import numpy as np
    F, C = len(mesh.polygons), len(mesh.loops)
    size = _get(mesh.polygons, "loop_total", F, np.int32)
    start = _get(mesh.polygons, "loop_start", F, np.int32)
    edge = _get(mesh.attributes[".corner_edge"].data, "value", C, np.int32)
    return np.repeat(np.arange(F), size), edge, start, size


def edge_angles(mesh):
    """(E,) degrees between the normals of each edge's first two faces (0 for edges of fewer
    faces) of an evaluated mesh."""
    import numpy as np
    E, F = len(mesh.edges), len(mesh.polygons)
    normals = _get(mesh.polygons, "normal", F, np.float32, 3).astype(np.float64)
    face, edge, _, _ = _corners(mesh)
    order = np.argsort(edge, kind="stable")
    e, f = edge[order], face[order]
    first = np.searchsorted(e, np.arange(E))
    count = np.bincount(e, minlength=E)
    two = np.flatnonzero(count >= 2)
    out = np.zeros(E)
    c = np.einsum("ij,ij->i", normals[f[first[two]]], normals[f[first[two] + 1]])
    out[two] = np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
    return out


def corner_normals(mesh):
    """(C, 3) float64 normals of the corners of an evaluated mesh (the file's split normals
    where the importer set custom normals)."""
    import numpy as np
    return _get(mesh.corner_normals, "vector", len(mesh.loops), np.float32, 3).astype(np.float64)


def weld(bpy, obj, distance: float):
    """Weld the vertices of the imported `obj` (the script's own copy, never the file)
    closer than `distance` (Blender's Merge by Distance, ``bmesh.ops.remove_doubles``),
    before creases are measured: an exporter's split seams (glTF splits every vertex where
    normals or UVs differ, so a cube arrives as six separate quads) leave no edge between
    two faces to measure. Returns the file's corner normals (C', 3) at the corners after
    the weld (Blender re-derives custom normals in the welded fans): they ride along as a
    corner attribute, so corners of faces the weld removes (made degenerate) take theirs
    away with them."""
    import bmesh
    import numpy as np
    mesh = obj.data
    normals = corner_normals(mesh.evaluated_get(bpy.context.evaluated_depsgraph_get()))
    carry = mesh.attributes.new(_WELD_NORMALS, "FLOAT_VECTOR", "CORNER")
    carry.data.foreach_set("vector", normals.astype(np.float32).ravel())
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=distance)
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()
    carry = mesh.attributes[_WELD_NORMALS]
    out = _get(carry.data, "vector", len(mesh.loops), np.float32, 3).astype(np.float64)
    mesh.attributes.remove(carry)
    return out


_WELD_NORMALS = ".gerbs_cli_file_normals"  # the imported copy's, removed after the weld


def split_normal_edges(mesh, normals, degrees: float = 1.0):
    """(E,) bool: the edges of two faces whose corners at either end carry normals more than
    `degrees` apart (split normals: the file's hard edges), from the corner normals
    ``normals`` (C, 3) of `mesh` (an evaluated mesh, the corners in its order)."""
    import numpy as np
    E, C = len(mesh.edges), len(mesh.loops)
    face, edge, start, size = _corners(mesh)
    prev = np.arange(C) - 1
    prev[start] = start + size - 1                  # each face's first corner: its last
    vert = _get(mesh.attributes[".corner_vert"].data, "value", C, np.int32)
    # every corner meets two of its face's edges: (edge, vertex, face, corner) twice
    e = np.concatenate([edge, edge[prev]])
    v, f, c = np.tile(vert, 2), np.tile(face, 2), np.tile(np.arange(C), 2)
    order = np.lexsort((f, v, e))
    e, v, c = e[order], v[order], c[order]
    key = e.astype(np.int64) * len(mesh.vertices) + v
    group = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])     # one per edge end
    count = np.diff(np.r_[group, len(key)])
    two = group[count == 2]                         # an edge end shared by two faces
    n1, n2 = normals[c[two]], normals[c[two + 1]]
    cos = np.einsum("ij,ij->i", n1, n2) / np.maximum(
        np.linalg.norm(n1, axis=1) * np.linalg.norm(n2, axis=1), 1e-300)
    out = np.zeros(E, bool)
    out[e[two[cos < np.cos(np.radians(degrees))]]] = True
    return out


def _split_seams(mesh) -> bool:
    """Whether vertices of `mesh` (the imported copy) share positions: a file split at its
    seams (glTF exporters split every vertex where normals or UVs differ)."""
    import numpy as np
    V = len(mesh.vertices)
    P = _get(mesh.vertices, "co", V, np.float32, 3)
    return V > 0 and len(np.unique(P, axis=0)) < V


def mark_creases(bpy, obj, angle=None, sharp=False, normals=None) -> int:
    """Fully crease (Blender's ``crease_edge`` = 1) the edges of the imported `obj` whose
    dihedral angle exceeds `angle` degrees and, with `sharp`, those marked sharp or whose
    two faces' split normals differ (``normals``: the file's corner normals (C, 3), from
    :func:`weld`; else the mesh's own); creases the file brought along are kept. Read from
    the evaluated mesh; returns the count."""
    import numpy as np
    mesh = obj.data.evaluated_get(bpy.context.evaluated_depsgraph_get())
    E = len(mesh.edges)
    old = mesh.attributes.get("crease_edge")
    w = np.zeros(E, np.float32) if old is None else _get(old.data, "value", E, np.float32)
    full = np.zeros(E, bool)
    if angle is not None:
        full |= edge_angles(mesh) > angle
    flag = mesh.attributes.get("sharp_edge")
    if sharp and flag is not None:
        full |= _get(flag.data, "value", E, bool)
    if sharp and mesh.has_custom_normals:
        full |= split_normal_edges(mesh, corner_normals(mesh) if normals is None else normals)
    w = np.where(full, np.float32(1.0), w)
    attr = obj.data.attributes.get("crease_edge") or \
        obj.data.attributes.new("crease_edge", "FLOAT", "EDGE")
    attr.data.foreach_set("value", w)
    obj.data.update()
    return int(full.sum())


def shade_smooth(obj) -> None:
    """``--shading smooth`` on the imported copy (never the file): every face smooth and
    no edge sharp but the fully creased ones (``crease_edge`` = 1, where the surface has a
    crease: its normals split there). A flat-shaded file's look would otherwise reach the
    output: its faces' flat shading ("s 0"), and the sharp edges Blender's importers mark
    between faces whose normals differ (an OBJ written flat with its normals: 961 of the
    Monkey's 1,005 edges), which the modifier carries onto the output's edges, splitting
    its normals along every cage edge."""
    import numpy as np
    mesh = obj.data
    mesh.shade_smooth()
    E = len(mesh.edges)
    crease = mesh.attributes.get("crease_edge")
    full = np.zeros(E, bool) if crease is None else \
        _get(crease.data, "value", E, np.float32) >= 1.0
    flag = mesh.attributes.get("sharp_edge")
    if not full.any():
        if flag is not None:
            mesh.attributes.remove(flag)
        return
    if flag is None:
        flag = mesh.attributes.new("sharp_edge", "BOOLEAN", "EDGE")
    flag.data.foreach_set("value", full)
    mesh.update()


# --- export ---------------------------------------------------------------------

@contextlib.contextmanager
def _stdout_silenced():
    """Blender's exporters print the temporary path they write to ("Writing to
    .../.gerbs-xyz/out.obj") on the process's standard output: not where the result
    goes, so not shown (our own lines are on stderr)."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def sidecars(out: Path) -> list[Path]:
    """The files an output may write beside itself: a .gltf's buffer (.bin), an .obj's
    material library (.mtl)."""
    side = {".gltf": ".bin", ".obj": ".mtl"}.get(out.suffix.lower())
    return [] if side is None else [out.with_suffix(side)]


def export_mesh(bpy, objects, out: Path, protected, make_folder: bool = False,
                up=None) -> None:
    """Export into a temporary folder beside `out`, then rename every file into
    place (sidecars first); refuse if one would replace a `protected` file. The folder
    of `out` must exist unless `make_folder` (the default output's ``out/``)."""
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = objects[0]
    try:
        if make_folder:
            out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=".gerbs-", dir=out.parent))
    except OSError as exc:
        raise UserError(f"cannot write {out}: {exc.strerror}") from None
    try:
        target = tmp / out.name
        ext = out.suffix.lower()
        with _stdout_silenced():
            if ext == ".obj":
                # materials in a .mtl beside it, where the input has any (as .glb keeps
                # them; a newcomer's walk found them dropped)
                bpy.ops.wm.obj_export(filepath=str(target), export_selected_objects=True,
                                      **axes(up),
                                      apply_modifiers=True, export_materials=any(
                                          len(o.data.materials) for o in objects))
            else:
                # a still surface: no animation (an input's morph weights channel would
                # point at a mesh without morph targets, an invalid file; an export test)
                bpy.ops.export_scene.gltf(filepath=str(target), use_selection=True,
                                          export_apply=True, export_animations=False,
                                          export_format="GLB" if ext == ".glb" else "GLTF_SEPARATE")
        produced = sorted(tmp.iterdir(), key=lambda p: p.name == out.name)  # main file last
        named = {out.name} | {q.name for q in sidecars(out)}   # names the output chooses
        for p in produced:
            dest = out.parent / p.name
            # an image the exporter writes beside a .gltf keeps its own name: only another
            # folder avoids it (an export test: "another output name" could never help)
            where = "another output name or folder" if p.name in named else \
                "another output folder"
            if any(_same_file(dest, q) for q in protected if q.exists()):
                raise UserError(f"writing {out.name} would replace {dest.name}, which the "
                                f"input uses; choose {where}")
            # a file of the user's that happens to share an image's name is not replaced
            # (an export test: an unrelated checker.png was overwritten with no word); the
            # same bytes (this command's earlier run) are
            if (p.name not in named and dest.exists()
                    and (not dest.is_file() or dest.read_bytes() != p.read_bytes())):
                raise UserError(f"writing {out.name} would replace {dest.name} beside it, a "
                                f"different file; choose {where}, or move that file")
        for p in produced:
            os.replace(p, out.parent / p.name)
    except OSError as exc:
        raise UserError(f"cannot write {out}: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def run(args, src: Path, out: Path, protected) -> None:
    settings = settings_from(args)
    import bpy

    import blender_addon
    from blender_addon import api
    from blender_addon.progress import silent, text_bar

    import logging

    logging.getLogger("blender_addon").setLevel(logging.CRITICAL)  # errors are ours to print
    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    try:
        objects = import_mesh(bpy, src, args.up_axis)
        if not objects:
            raise UserError(f"{args.input} contains no mesh")
        for obj in objects:  # what a still surface leaves out: said, not dropped silently
            rigged = obj.find_armature() is not None
            keys = obj.data.shape_keys is not None
            if rigged or keys:
                what = " and ".join(x for x, y in (("its skin (armature)", rigged),
                                                   ("its shape keys (morph targets)", keys)) if y)
                print(f"warning: {obj.name}: {what} and animation are not written: the "
                      f"output is the surface of the mesh as imported", file=sys.stderr)
        for obj in objects:
            if args.crease_angle is not None or args.sharp_creases:
                # welded first: an exporter's split seams leave no edge between two faces
                normals = None if args.merge_distance is None else \
                    weld(bpy, obj, args.merge_distance)
                n = mark_creases(bpy, obj, args.crease_angle, args.sharp_creases, normals)
                seams = "" if n or normals is not None or not _split_seams(obj.data) else (
                    " (vertices share positions: the file is split at its seams, as glTF "
                    "exporters write it; --merge-distance 0 welds them first)")
                if not args.quiet or seams:
                    print(f"{obj.name}: {n} edges creased{seams}", file=sys.stderr)
            if args.shading == "smooth":
                shade_smooth(obj)
            if not args.quiet:
                print(f"{obj.name}: {len(obj.data.vertices)} vertices, "
                      f"{len(obj.data.polygons)} faces", file=sys.stderr)
            try:
                api.add_surface(obj, progress=silent if args.quiet else text_bar(), **settings)
            except ValueError as exc:
                raise UserError(f"{obj.name} in {args.input}: {cli_words(str(exc))}") from None
            info = api.status(obj)
            for warning in info.get("warnings", ()):  # repairs: reported, not errors
                print(f"warning: {obj.name}: {cli_words(warning.message)}", file=sys.stderr)
            if not args.quiet:
                # faces as written (quads in quads), and the triangles they make
                print(f"{obj.name}: surface with {info['points']} points, {info['faces']} "
                      f"faces ({info['triangles']} triangles) in "
                      f"{info['build_seconds']:.2f} s", file=sys.stderr)
        bpy.context.view_layer.update()
        rounding = obj_rounding(bpy, objects) if out.suffix.lower() == ".obj" else ""
        if rounding:
            print(f"warning: {rounding}", file=sys.stderr)
        if not args.quiet:
            print(f"writing {out} ...", file=sys.stderr)
        export_mesh(bpy, objects, out, protected, make_folder=args.default_output,
                    up=args.up_axis)
    finally:
        blender_addon.unregister()


def main(argv=None) -> int:
    sys.path.insert(0, str(ROOT))
    try:
        import bpy  # noqa: F401  (Blender's module: only the project's environment has it)
    except ImportError as exc:
        if isinstance(exc, ModuleNotFoundError) and exc.name == "bpy":
            print(f"\nerror: {Path(sys.executable).name} has no Blender 'bpy' module; run this "
                  f"with the project's environment, {ROOT / '.venv' / 'bin' / 'python'} (the "
                  f"README's first command installs it)", file=sys.stderr)
        else:  # bpy is there, but a module or library it needs does not load
            print(f"\nerror: Blender's 'bpy' module does not load: {' '.join(str(exc).split())}",
                  file=sys.stderr)
        return USER_ERROR
    try:
        args = parse_args(sys.argv[1:] if argv is None else argv)
        src, out = check_paths(args)
        gltf = src.suffix.lower() in (".gltf", ".glb")
        protected = [src] + (gltf_references(src) if gltf else
                             obj_references(src) if src.suffix.lower() == ".obj" else [])
        if any(_same_file(out, p) for p in protected if p.exists()):
            raise UserError(f"output {args.output} is a file the input uses; choose another name")
        for side in sidecars(out):  # said before the build (export_mesh checks again)
            if any(_same_file(side, p) for p in protected if p.exists()):
                raise UserError(f"writing {out.name} would replace {side.name}, which the "
                                f"input uses; choose another output name or folder")
        existed = out.exists()   # said below: cube.obj and cube.stl share a default name
        run(args, src, out, protected)
    except UserError as exc:
        message = " ".join(str(exc).split())  # one line, whatever the message held
        print(f"\nerror: {message}", file=sys.stderr)
        return USER_ERROR
    print(f"wrote {out}" + (" (replacing the file that was there)" if existed else ""),
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
