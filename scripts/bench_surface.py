"""Benchmark GERBS blending surfaces against Blender's Subdivision Surface modifier.

For Suzanne, an icosphere and 32x32 and 64x64 quad grids at resolutions giving about 8k,
32k and 126k output points: build time (BlendingSurface + stencil from scratch; the
stencil's share printed separately),
update time (W @ X, every vertex moved; and one vertex moved by Stencil.apply_moved, what a
drag's step costs), memory (tracemalloc peak of the build), nnz per row; and,
when ``import bpy`` works, Blender's Subdivision Surface modifier at the matching
level (level L <-> resolution 2**L) in the same run: build = add the modifier and
evaluate the depsgraph from scratch; update = move one vertex and evaluate again.
Medians of repeats; ratios GERBS / Subsurf. The GERBS builds and the Subsurf
builds alternate (one of each per round), so both see the same machine load.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/bench_surface.py [--repeats 5] [--tables]

Every build is from scratch (the core keeps no process-wide cache). --tables also
prints the Franke F1 convergence table (N = 100 ... 6400). --scaling prints the build's
CPU time over quad grids 32x32, 64x64, 128x128 at r = 8 (minimum of repeats) and the
vertex-count exponent (the least-squares slope of log time against log vertices, and the
slope of each step; issue 15 asks <= 1.05).
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from gerbs_core.datasets import primitives as P  # noqa: E402
from gerbs_core.mesh.surface import BlendingSurface  # noqa: E402


def median_time(fn, repeats):
    ts = []
    out = None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts), out


def gerbs_case(V, F, r, repeats, subsurf_build=None):
    """GERBS timings; with ``subsurf_build`` (a function timing one Subsurf build) the
    builds alternate with Subsurf builds, so both see the same machine load
    (returned as ``ss_build``, the median)."""
    tst = []

    def build():
        s = BlendingSurface(V, F)
        t = time.perf_counter()
        st = s.stencil(r)
        tst.append(time.perf_counter() - t)
        return s, st

    build()  # warm-up (imports, kernel tables)
    tst.clear()
    tcold, tss = [], []
    for _ in range(repeats):
        t = time.perf_counter()
        s, st = build()
        tcold.append(time.perf_counter() - t)
        if subsurf_build is not None:
            tss.append(subsurf_build())
    tb = statistics.median(tcold)
    X = V.copy()
    X[0] += 1e-3

    def update():
        return st.apply(X)

    tu, _ = median_time(update, max(repeats, 20))
    # One vertex moved, as a drag does (Stencil.apply_moved): the first step takes the
    # vertex's columns of W, every further step of the same drag reuses them.
    pts = st.apply(V)
    moved = np.array([len(V) // 2])
    sign = [1.0]

    def drag_step():
        st.apply_moved(pts, moved, np.full((1, V.shape[1]), 1e-3 * sign[0]))
        sign[0] = -sign[0]

    t = time.perf_counter()
    drag_step()
    t1first = time.perf_counter() - t
    t1, _ = median_time(drag_step, max(repeats, 20))
    tracemalloc.start()
    build()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return dict(points=st.shape[0], build=tb, stencil=statistics.median(tst[:repeats]),
                update=tu, one=t1, one_first=t1first, mem=peak / 1e6,
                nnz=st.nnz_per_row(), eps0=s.eps0,
                ss_build=statistics.median(tss) if tss else None)


def blender_case(bpy, V, F, level, repeats):
    """Subsurf set-up; returns (build (one timed from-scratch build), update timing)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    mesh = bpy.data.meshes.new("bench")
    mesh.from_pydata([tuple(map(float, v)) for v in V], [], [tuple(map(int, f)) for f in F])
    mesh.update()
    obj = bpy.data.objects.new("bench", mesh)
    bpy.context.scene.collection.objects.link(obj)
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    counts = []

    def build():
        for m in list(obj.modifiers):
            obj.modifiers.remove(m)
        dg.update()
        t = time.perf_counter()
        mod = obj.modifiers.new("subsurf", "SUBSURF")
        mod.levels = level
        mod.render_levels = level
        dg.update()
        n = len(obj.evaluated_get(dg).data.vertices)
        counts.append(n)
        return time.perf_counter() - t

    build()
    step = [1e-3]

    def update():
        mesh.vertices[0].co.x += step[0]
        step[0] = -step[0]
        mesh.update()
        t = time.perf_counter()
        dg.update()
        len(obj.evaluated_get(dg).data.vertices)
        return time.perf_counter() - t

    update()
    tu = statistics.median([update() for _ in range(max(repeats, 10))])
    return build, dict(points=counts[-1], update=tu)


def franke_table():
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "core"))
    from test_surface_convergence import franke_errors
    rows = []
    for n in (10, 20, 40, 80):
        t = time.perf_counter()
        emax, erms = franke_errors(n)
        rows.append((n * n, 1.0 / (n - 1), emax, erms, time.perf_counter() - t))
    print("\nFranke F1 on flat jittered Delaunay (resolution 4)")
    print(f"{'N':>6} {'h':>8} {'max err':>10} {'order':>6} {'rms err':>10} {'order':>6} "
          f"{'time s':>7}")
    prev = None
    for N, h, a, b, t in rows:
        oa = ob = float("nan")
        if prev:
            oa = np.log(prev[2] / a) / np.log(prev[1] / h)
            ob = np.log(prev[3] / b) / np.log(prev[1] / h)
        print(f"{N:6d} {h:8.4f} {a:10.3e} {oa:6.2f} {b:10.3e} {ob:6.2f} {t:7.2f}")
        prev = (N, h, a, b)


def scaling(repeats, sides=(32, 64, 128), r=8):
    """Build CPU seconds (BlendingSurface + stencil, minimum of ``repeats``) over quad grids
    and the exponent of the vertex count."""
    nv, ts = [], []
    for n in sides:
        V, F = P.grid(n, n)
        best = np.inf
        for _ in range(repeats):
            t = time.process_time()
            BlendingSurface(V, F).stencil(r)
            best = min(best, time.process_time() - t)
        nv.append(len(V))
        ts.append(best)
        print(f"grid {n}x{n} ({len(V)} vertices) r = {r}: build {best:.3f} CPU s", flush=True)
    slope = np.polyfit(np.log(nv), np.log(ts), 1)[0]
    steps = np.diff(np.log(ts)) / np.diff(np.log(nv))
    print(f"vertex-count exponent of the build: {slope:.2f} over all sizes; step by step "
          + ", ".join(f"{a}->{b}: {e:.2f}" for a, b, e in zip(sides, sides[1:], steps))
          + " (issue 15: <= 1.05; the last step is the one fixed costs do not flatter)")
    return slope


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--tables", action="store_true")
    ap.add_argument("--quick", action="store_true", help="Suzanne at level 2 only (a smoke run)")
    ap.add_argument("--scaling", action="store_true",
                    help="only the build's CPU time over grids 32-128 and its exponent")
    args = ap.parse_args()
    if args.scaling:
        scaling(max(1, min(args.repeats, 3)))
        return
    try:
        import bpy  # noqa: F401
    except ImportError:
        bpy = None
    meshes = {"suzanne": P.suzanne(), "icosphere(3)": P.icosphere(3), "grid 32x32": P.grid(32, 32),
              "grid 64x64": P.grid(64, 64)}
    print("build: BlendingSurface + stencil from scratch; update: W @ X (every vertex moved); "
          "1-vert: one vertex moved (Stencil.apply_moved, a drag's step; first = the drag's "
          "first step, which takes the vertex's columns); Subsurf (ss) at level L = log2 r, "
          "its update = one vertex moved and the depsgraph evaluated")
    print(f"{'mesh':13} {'L/r':>4} {'points':>7} {'build s':>8} {'stencil s':>9} "
          f"{'update ms':>9} {'1-vert ms':>9} {'first ms':>8} "
          f"{'mem MB':>7} "
          f"{'nnz/row':>7} {'eps0':>6} | {'ss points':>9} {'ss build s':>10} {'ss upd ms':>9} | "
          f"{'build x':>7} {'update x':>8} {'1-vert x':>8}")
    for name, (V, F) in meshes.items():
        if args.quick and name != "suzanne":
            continue
        for level in ((2,) if args.quick else (2, 3) if name == "grid 64x64" else (2, 3, 4)):
            r = 2 ** level
            ss_build, b = (blender_case(bpy, V, F, level, args.repeats) if bpy is not None
                           else (None, None))
            g = gerbs_case(V, F, r, args.repeats, ss_build)
            line = (f"{name:13} {level}/{r:<2} {g['points']:7d} {g['build']:8.3f} "
                    f"{g['stencil']:9.3f} "
                    f"{g['update'] * 1e3:9.2f} {g['one'] * 1e3:9.3f} {g['one_first'] * 1e3:8.2f} "
                    f"{g['mem']:7.0f} {g['nnz']:7.1f} {g['eps0']:6.3f}")
            if bpy is not None:
                b["build"] = g["ss_build"]
                line += (f" | {b['points']:9d} {b['build']:10.3f} {b['update'] * 1e3:9.2f} | "
                         f"{g['build'] / b['build']:7.2f} "
                         f"{g['update'] / b['update']:8.3f} {g['one'] / b['update']:8.3f}")
            print(line, flush=True)
    if args.tables:
        franke_table()


if __name__ == "__main__":
    main()
