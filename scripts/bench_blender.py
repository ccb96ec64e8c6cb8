#!/usr/bin/env python
"""GERBS modifier vs Blender's Subdivision Surface modifier, in one bpy run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/bench_blender.py [--repeats 5] [--quick]
    ... [--edit-only] --large   (only the Edit Mode timings on the 35k mesh, ~2-4 min)

For Suzanne, an icosphere and a 32x32 grid, and Subsurf levels giving ~30k and
~120k output vertices, the GERBS resolution is the one whose output vertex
count is closest to Subsurf's (both counts printed; must agree within 5%).
Times (medians of repeats, seconds), each including the depsgraph evaluation
and access to the evaluated mesh's positions:
  build   add the modifier to a mesh without one, evaluate (from scratch: the
          core keeps no process-wide cache). One untimed build of each modifier
          first (imports, kernel tables, Blender's lazy set-up), then the timed
          repeats, interleaved (Subsurf, GERBS in every round) so both see the
          same machine load.
  1 vert  move one base vertex, evaluate (GERBS with Rest Shape "Follow", the
          default: a rebuild; "1v bound": Rest Shape "Bound", the sparse update)
  all     move every base vertex, evaluate (Rest Shape "Bound")
--edit (with --large: the 35k-vertex triangle mesh, else Suzanne) times Edit Mode
updates at resolution 2, Rest Shape Bound (what a drag of a Follow surface previews
too): a selection change through the select operator (``select_all``, which tags
only the selection, as every select tool does), a selection change by a script
(bmesh, then ``update_edit_mesh``: that tags the geometry, so Blender evaluates
every modifier), and a one-vertex move (bmesh, then a depsgraph update), with the
GERBS modifier, with the anchors instead (Blender's Subdivision Surface, level 2, and a
do-nothing Geometry Nodes modifier, input to output: what any modifier costs there,
Blender converting the edit mesh for it) and with no modifier evaluated (each one's
"Edit Mode" toggle off: Blender then shows the edit mesh as it is), alternated round by
round; each the median of 3 within a round. "x": the median over the rounds of the
ratio to no modifier within a round (so a target of 1.5x no modifier is below what a
do-nothing modifier costs), and for GERBS also to the do-nothing GN. Timed: the edit
and the depsgraph update; of it, the time in the add-on's handler ("ours"; the rest is
Blender's: converting the edit mesh, evaluating the node group, twice for a move);
apart, reading the evaluated positions ("read", the surface's).
"pair" is the median over the rounds of (GERBS / Subsurf) within a round,
less sensitive to load changing during the run than the ratio of the medians.
The add-on's node group is made once (printed: "group"; it is removed with the
last GERBS modifier, so a fake user keeps it through the add/remove rounds).
Targets (issue 5): GERBS update <= 0.5x Subsurf at ~120k vertices; build <= 4x
(from scratch).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from bench_edit import edit_mode, evaluated_positions  # noqa: E402  (after the path)


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def height_field(bpy, n: int, name: str):
    """A triangulated n x n height-field grid z = 0.1 sin(3x) cos(2y) (n^2 vertices)."""
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.stack([x.ravel(), y.ravel(), (0.1 * np.sin(3 * x) * np.cos(2 * y)).ravel()], 1)
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = (idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(),
                  idx[1:, :-1].ravel())
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(V.tolist(), [], F.tolist())
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def make_objects(bpy, large: bool):
    bpy.ops.wm.obj_import(filepath=str(ROOT / "examples" / "suzanne.obj"))
    suzanne = bpy.context.selected_objects[0]
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=1.0)
    ico = bpy.context.active_object
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=32, y_subdivisions=32, size=2.0)
    grid = bpy.context.active_object
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=64, y_subdivisions=64, size=2.0)
    grid64 = bpy.context.active_object
    objects = {"suzanne": suzanne, "icosphere": ico, "grid 32x32": grid, "grid 64x64": grid64}
    if large:
        objects["tri 35k"] = height_field(bpy, 188, "tri35k")
    return objects


def subsurf_count(bpy, obj, level):
    mod = obj.modifiers.new("bench", "SUBSURF")
    mod.levels = level
    n = len(evaluated_positions(bpy, obj)) // 3
    obj.modifiers.remove(mod)
    return n


def closest_resolution(obj, target):
    from blender_addon import mesh_io
    from gerbs_core.mesh.topology import MeshTopology
    from gerbs_core.mesh.lattice import output_counts

    offsets, corners = mesh_io.read_topology(obj.data)
    topo = MeshTopology(mesh_io.faces_from_csr(offsets, corners), len(obj.data.vertices))
    best = min(range(1, 65), key=lambda r: abs(output_counts(topo, r)[0] - target))
    return best, output_counts(topo, best)[0]


class Mover:
    """Moves base vertices through the position attribute (same for both modifiers)."""

    def __init__(self, obj):
        self.mesh = obj.data
        self.X = np.empty(len(self.mesh.vertices) * 3, dtype=np.float32)
        self.mesh.attributes["position"].data.foreach_get("vector", self.X)
        self.k = 0

    def one(self):
        self.k += 1
        self.X[0] += 1e-3 * (-1) ** self.k
        self._write()

    def all(self):
        self.k += 1
        self.X += 1e-3 * (-1) ** self.k
        self._write()

    def _write(self):
        self.mesh.attributes["position"].data.foreach_set("vector", self.X)
        self.mesh.update()


def bench_pair(bpy, obj, level, repeats):
    from blender_addon import api

    n_sub = subsurf_count(bpy, obj, level)
    r, n_gerbs = closest_resolution(obj, n_sub)
    rows = {}
    mover = Mover(obj)

    def sub_build():
        mod = obj.modifiers.new("bench", "SUBSURF")
        mod.levels = level
        evaluated_positions(bpy, obj)

    def sub_clear():
        obj.modifiers.clear()
        evaluated_positions(bpy, obj)

    def gerbs_build(rest="follow"):
        api.add_surface(obj, resolution=r, rest=rest)
        evaluated_positions(bpy, obj)

    def gerbs_clear():
        api.remove(obj)
        evaluated_positions(bpy, obj)

    def timed(build, clear):
        clear()
        t0 = time.perf_counter()
        build()
        t = time.perf_counter() - t0
        clear()
        return t

    # builds interleaved (S, G per round) so that both modifiers see the
    # same machine load; one untimed build of each first
    timed(sub_build, sub_clear)
    timed(gerbs_build, gerbs_clear)
    builds = {"subsurf": [], "gerbs": []}
    for _ in range(max(3, repeats)):
        builds["subsurf"].append(timed(sub_build, sub_clear))
        builds["gerbs"].append(timed(gerbs_build, gerbs_clear))
    def moves():
        one = median_time(lambda: (mover.one(), evaluated_positions(bpy, obj)), repeats)
        allv = median_time(lambda: (mover.all(), evaluated_positions(bpy, obj)), repeats)
        return one, allv

    sub_build()
    rows["subsurf"] = (statistics.median(builds["subsurf"]),) + moves()
    sub_clear()
    gerbs_build()
    one_follow = moves()[0]
    gerbs_clear()
    gerbs_build(rest="bound")
    rows["gerbs"] = (statistics.median(builds["gerbs"]), one_follow) + moves()
    gerbs_clear()
    # median over rounds of the build ratio within each round (robust to load drift)
    rows["paired"] = statistics.median(g / s for g, s in zip(builds["gerbs"], builds["subsurf"]))
    return n_sub, n_gerbs, r, rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="only the ~30k level")
    ap.add_argument("--large", action="store_true", help="also the 35k-vertex triangle mesh")
    ap.add_argument("--edit", action="store_true", help="Edit Mode timings (35k mesh with --large)")
    ap.add_argument("--edit-only", action="store_true",
                    help="only the Edit Mode timings (implies --edit)")
    ap.add_argument("--only", nargs="*", help="only these meshes (names as printed)")
    args = ap.parse_args(argv)
    args.edit = args.edit or args.edit_only
    import bpy

    import blender_addon

    from blender_addon import geometry_nodes as gn

    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    t0 = time.perf_counter()
    gn.ensure_group().use_fake_user = True  # kept through the add/remove rounds
    print(f"group: {time.perf_counter() - t0:.3f} s to make the node group (once per file)")
    objects = make_objects(bpy, args.large)
    if args.edit_only:
        edit_mode(bpy, objects["tri 35k" if args.large else "suzanne"], args.repeats)
        blender_addon.unregister()
        return 0
    levels = {"suzanne": (3, 4), "icosphere": (3, 4), "grid 32x32": (3, 4), "grid 64x64": (2, 3),
              "tri 35k": (2,)}   # triangles: level 3 matches r = 10 (3.5M points, over budget)
    print(f"{'mesh':<11} {'lvl':>3} {'subsurf pts':>11} {'r':>3} {'gerbs pts':>10} {'diff':>6} | "
          f"{'build S':>8} {'build G':>8} {'G/S':>5} {'pair':>5} | "
          f"{'1vert S':>8} {'1vert G':>8} {'G/S':>5} {'1v bound':>8} {'G/S':>5} | "
          f"{'all S':>8} {'all G':>8} {'G/S':>5}")
    for name, obj in objects.items():
        if args.only and name not in args.only:
            continue
        for level in levels[name][: 1 if args.quick else 2]:
            n_sub, n_g, r, rows = bench_pair(bpy, obj, level, args.repeats)
            (bs, os_, as_), (bg, og, obg, ag) = rows["subsurf"], rows["gerbs"]
            print(f"{name:<11} {level:>3} {n_sub:>11} {r:>3} {n_g:>10} {100 * (n_g - n_sub) / n_sub:>5.1f}% | "
                  f"{bs:>8.4f} {bg:>8.4f} {bg / bs:>5.2f} {rows['paired']:>5.2f} "
                  "| "
                  f"{os_:>8.4f} {og:>8.4f} {og / os_:>5.2f} {obg:>8.4f} {obg / os_:>5.2f} | "
                  f"{as_:>8.4f} {ag:>8.4f} {ag / as_:>5.2f}", flush=True)
    if args.edit:
        edit_mode(bpy, objects["tri 35k" if args.large else "suzanne"], args.repeats)
    blender_addon.unregister()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
