#!/usr/bin/env python
"""What the add-on's handlers cost for updates that do not touch a GERBS object.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/bench_handlers.py [--objects 2000] [--rounds 150]

A scene of N unrelated mesh objects (cubes, each with its own mesh) and one
Suzanne with a GERBS modifier (resolution 8). Timed, each a median over
``--updates`` updates within a round:

  move    ``cube.location.x += 1e-4; view_layer.update()`` (a transform update)
  edit    write a cube's vertex positions, ``mesh.update(); view_layer.update()``
          (a geometry update of an unrelated mesh)

Set-ups, alternated every ``--batch`` updates so that all see the same machine
load (on a shared machine the load drifts by more than the effect): the add-on
registered; its handlers removed (what it costs per update is its handlers:
the modifier and its result stay in the scene either way, as after
``unregister``); a do-nothing Python ``depsgraph_update_post`` handler instead
(the floor any Python handler costs: Blender calls into Python for every
update). Reported: the median over batches of each, and "pair", the median
over rounds of (set-up / no handlers) within a round. Target (issue 16): the
add-on's pair <= 1.10.
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


def build_scene(bpy, n_objects: int):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    cube = None
    for i in range(n_objects):
        mesh = bpy.data.meshes.new(f"cube{i}")
        mesh.from_pydata([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], [],
                         [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                          (1, 5, 7, 3)])
        cube = bpy.data.objects.new(f"cube{i}", mesh)
        cube.location = (3.0 * (i % 50), 3.0 * (i // 50), 0.0)
        scene.collection.objects.link(cube)
    bpy.ops.wm.obj_import(filepath=str(ROOT / "examples" / "suzanne.obj"))
    suzanne = bpy.context.selected_objects[0]
    bpy.context.view_layer.update()
    return cube, suzanne


def timed_updates(bpy, fn, n: int) -> float:
    times = []
    for k in range(n):
        t0 = time.perf_counter()
        fn(k)
        bpy.context.view_layer.update()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=150)
    ap.add_argument("--batch", type=int, default=5, help="updates per set-up and round")
    args = ap.parse_args(argv)
    import bpy

    import blender_addon
    from blender_addon import api

    cube, suzanne = build_scene(bpy, args.objects)
    blender_addon.register()
    api.add_surface(suzanne, resolution=8)
    co = np.empty(24, dtype=np.float32)
    cube.data.attributes["position"].data.foreach_get("vector", co)

    def move(k):
        cube.location.x += 1e-4 * (-1) ** k

    def edit(k):
        co[2] += 1e-4 * (-1) ** k
        cube.data.attributes["position"].data.foreach_set("vector", co)
        cube.data.update()

    def noop(scene, depsgraph):
        pass

    from blender_addon import handlers

    ours = [(name, func) for name, func in handlers._HANDLERS
            if name in ("depsgraph_update_post", "frame_change_post")]
    setups = {"add-on": ours, "without": [], "noop": [("depsgraph_update_post", noop)]}
    rows = {(name, setup): [] for name in ("move", "edit") for setup in setups}
    for _ in range(args.rounds):
        for setup, funcs in setups.items():
            for name, func in ours:
                handlers._remove(name, func)
            for name, func in funcs:
                getattr(bpy.app.handlers, name).append(func)
            for name, fn in (("move", move), ("edit", edit)):
                timed_updates(bpy, fn, 1)  # the first update after a switch: not timed
                rows[name, setup].append(timed_updates(bpy, fn, args.batch))
            for name, func in funcs:
                getattr(bpy.app.handlers, name).remove(func)
    blender_addon.register()
    print(f"{args.objects} unrelated objects + 1 GERBS object; {args.rounds} rounds of "
          f"{args.batch} updates per set-up")
    print(f"{'update':<6} {'add-on ms':>10} {'without ms':>11} {'no-op ms':>9} "
          f"{'pair add-on':>12} {'pair no-op':>11}")
    for name in ("move", "edit"):
        med = {setup: statistics.median(rows[name, setup]) for setup in setups}
        pair = {setup: statistics.median(a / b for a, b in zip(rows[name, setup],
                                                                rows[name, "without"]))
                for setup in ("add-on", "noop")}
        print(f"{name:<6} {1e3 * med['add-on']:>10.3f} {1e3 * med['without']:>11.3f} "
              f"{1e3 * med['noop']:>9.3f} {pair['add-on']:>12.3f} {pair['noop']:>11.3f}",
              flush=True)
    blender_addon.unregister()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
