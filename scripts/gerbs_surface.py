#!/usr/bin/env python
"""Main job: a GERBS blending surface of a mesh file, headless, through Blender.

    .venv/bin/python scripts/gerbs_surface.py        # bundled sample -> out/suzanne_gerbs.glb
    .venv/bin/python scripts/gerbs_surface.py examples/suzanne.obj -o out.glb
    .venv/bin/python scripts/gerbs_surface.py in.ply -o out.obj --resolution 6 --degree 3

Reads OBJ, glTF (.gltf/.glb), PLY or STL with Blender's own importers (vertices
merged for glTF/STL, whose files split them), adds the GERBS Blending Surface
modifier to every imported mesh (``blender_addon.api``), and writes OBJ or glTF
(by the output extension) with Blender's exporters, modifiers applied. A text
progress bar goes to stderr. An invalid mesh prints the problem and its
location and exits with status 2 without writing anything.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "examples" / "suzanne.obj"
INPUTS = (".obj", ".gltf", ".glb", ".ply", ".stl")
OUTPUTS = (".obj", ".gltf", ".glb")


def parse_args(argv):
    p = argparse.ArgumentParser(description="GERBS blending surface of a mesh file (headless Blender)")
    p.add_argument("input", nargs="?", type=Path, default=SAMPLE,
                   help=f"mesh file {INPUTS} (default: the bundled {SAMPLE.relative_to(ROOT)})")
    p.add_argument("-o", "--output", type=Path, default=None,
                   help=f"output {OUTPUTS} (default: out/<input name>_gerbs.glb under the current directory)")
    p.add_argument("--resolution", type=int, default=4, help="segments per mesh edge (default 4)")
    p.add_argument("--degree", type=int, default=2, help="local polynomial degree 0..3 (default 2)")
    p.add_argument("--kernel", default="erbs", choices=["erbs", "bfbs", "logistic", "affine"])
    p.add_argument("--mode", default="regular", choices=["regular", "metric"])
    p.add_argument("--boundary", default="keep", choices=["keep", "straighten"])
    for name in ("alpha", "beta", "gamma", "lam", "sigma"):
        p.add_argument(f"--{name}", type=float, default=None, help=f"ERBS parameter {name}")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    if args.output is None:
        args.output = Path.cwd() / "out" / f"{args.input.stem}_gerbs.glb"
    if args.input.suffix.lower() not in INPUTS:
        p.error(f"input must be one of {INPUTS}, got {args.input.name}")
    if args.output.suffix.lower() not in OUTPUTS:
        p.error(f"output must be one of {OUTPUTS}, got {args.output.name}")
    if not args.input.is_file():
        p.error(f"input file {args.input} does not exist")
    return args


def import_mesh(bpy, path: Path):
    """Import with Blender's importer; return the new mesh objects."""
    before = set(bpy.data.objects)
    ext = path.suffix.lower()
    if ext == ".obj":
        bpy.ops.wm.obj_import(filepath=str(path))
    elif ext in (".gltf", ".glb"):
        bpy.ops.import_scene.gltf(filepath=str(path), merge_vertices=True)
    elif ext == ".ply":
        bpy.ops.wm.ply_import(filepath=str(path))
    elif ext == ".stl":
        bpy.ops.wm.stl_import(filepath=str(path))
    objects = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    if ext in (".stl", ".gltf", ".glb"):
        import bmesh
        for obj in objects:  # these formats duplicate vertices per face / per seam
            bm = bmesh.new()
            bm.from_mesh(obj.data)
            bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=1e-7)
            bm.to_mesh(obj.data)
            bm.free()
    return objects


def export_mesh(bpy, objects, path: Path) -> None:
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = objects[0]
    ext = path.suffix.lower()
    path.parent.mkdir(parents=True, exist_ok=True)
    if ext == ".obj":
        bpy.ops.wm.obj_export(filepath=str(path), export_selected_objects=True,
                              apply_modifiers=True, export_materials=False)
    else:
        bpy.ops.export_scene.gltf(filepath=str(path), use_selection=True, export_apply=True,
                                  export_format="GLB" if ext == ".glb" else "GLTF_SEPARATE")


def main(argv=None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    sys.path.insert(0, str(ROOT))
    import bpy

    import blender_addon
    from blender_addon import api
    from blender_addon.progress import silent, text_bar

    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    try:
        objects = import_mesh(bpy, args.input)
        if not objects:
            print(f"error: {args.input} contains no mesh", file=sys.stderr)
            return 1
        settings = dict(resolution=args.resolution, degree=args.degree, kernel=args.kernel,
                        mode=args.mode, boundary=args.boundary)
        settings.update({k: getattr(args, k) for k in ("alpha", "beta", "gamma", "lam", "sigma")
                         if getattr(args, k) is not None})
        for obj in objects:
            if not args.quiet:
                print(f"{obj.name}: {len(obj.data.vertices)} vertices, "
                      f"{len(obj.data.polygons)} faces", file=sys.stderr)
            try:
                api.add_surface(obj, progress=silent if args.quiet else text_bar(), **settings)
            except ValueError as exc:
                print(f"\nerror: {obj.name} in {args.input}: {exc}", file=sys.stderr)
                return 2
            if not args.quiet:
                info = api.status(obj)
                print(f"{obj.name}: surface with {info['points']} points, "
                      f"{info['triangles']} triangles in {info['build_seconds']:.2f} s",
                      file=sys.stderr)
        bpy.context.view_layer.update()
        export_mesh(bpy, objects, args.output)
        print(f"wrote {args.output}", file=sys.stderr)
        return 0
    finally:
        blender_addon.unregister()


if __name__ == "__main__":
    raise SystemExit(main())
