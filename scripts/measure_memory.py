"""Peak memory of a ~1M-output-point GERBS build, next to the memory guard's estimate.

    OPENBLAS_NUM_THREADS=1 python scripts/measure_memory.py [--points 1000000] [--mesh suzanne|grid|tri35k]

For the chosen mesh (Suzanne by default) the smallest resolution giving at least
``--points`` output points is used. Each measurement runs in a fresh child
process (so peaks do not mix) and reports:

* ``estimate``: what BlendingSurface.lattice() compares with ``memory_budget``
  (the guard; ResourceLimitError beyond; ``--budget`` also sizes the evaluation steps);
* ``tracemalloc peak``: the largest traced allocation total (numpy buffers are
  traced) during the call, above what was allocated before it;
* ``RSS peak``: resource.getrusage ru_maxrss of the child, minus its RSS right
  before the call (Linux: KiB) -- includes allocator slack, not only live arrays.

Stages: ``stencil`` (what the Blender add-on builds: sparse W with W @ X the
points), ``tessellate`` (points, triangles, normals by direct evaluation) and
``build`` (the whole job from the cage: the surface's model -- repair, covers,
fits, the fair-shape choice and coupling -- then the stencil and W @ X), whose
peak the guard does not estimate (it guards the output's size).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout's gerbs_core


def _mesh(name):
    import numpy as np

    from gerbs_core.datasets import primitives

    if name == "suzanne":
        return primitives.suzanne()
    if name == "grid":
        return primitives.grid(100, 100)
    if name == "tri35k":  # bench_blender's 35,344-vertex triangulated height field
        V, F = primitives.grid(187, kind="tri")
        V[:, 2] = 0.1 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
        return V, F
    raise SystemExit(f"unknown mesh {name!r}")


def _resolution_for(topology, points: int) -> int:
    from gerbs_core.mesh.lattice import output_counts

    r = 1
    while output_counts(topology, r)[0] < points:
        r += 1
    return r


def guard_estimate(X, faces, resolution: int, budget: float, **kw) -> float:
    """The guard's estimate in bytes for a surface with ``memory_budget=budget`` (the
    evaluation steps, hence the estimate, are sized for the budget)."""
    from gerbs_core import BlendingSurface

    return float(BlendingSurface(X, faces, memory_budget=budget, **kw).memory_estimate(resolution))


def child(mesh: str, points: int, stage: str, trace: bool, budget: float) -> dict:
    """Run one stage in this process and return its measurements."""
    import resource
    import time
    import tracemalloc

    import numpy as np

    from gerbs_core import BlendingSurface
    from gerbs_core.mesh.lattice import output_counts

    from gerbs_core.mesh.topology import MeshTopology

    X, faces = _mesh(mesh)
    topology = MeshTopology(faces, len(X))  # (the repair changes nothing on these meshes)
    r = _resolution_for(topology, points)
    P, T = output_counts(topology, r)
    # "build" measures the whole job in a fresh process: nothing is built before it
    surface = None if stage == "build" else BlendingSurface(X, faces, memory_budget=budget)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    with open("/proc/self/statm") as f:
        cur0 = int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    if trace:
        tracemalloc.start()
        base = tracemalloc.get_traced_memory()[0]
    t0 = time.perf_counter()
    if stage == "build":
        out = BlendingSurface(X, faces, memory_budget=budget).stencil(r).apply(X)
    elif stage == "stencil":
        out = surface.stencil(r).apply(X)
    else:
        out = surface.tessellate(r)[0]
    seconds = time.perf_counter() - t0
    res = dict(mesh=mesh, stage=stage, resolution=r, points=P, triangles=T,
               seconds=seconds, finite=bool(np.all(np.isfinite(out))))
    if trace:
        res["tracemalloc_peak"] = tracemalloc.get_traced_memory()[1] - base
        tracemalloc.stop()
    else:
        rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        res["rss_peak_total"] = rss1
        res["rss_peak_above_start"] = rss1 - max(rss0, cur0) if rss1 > rss0 else 0
        res["rss_start"] = cur0
    res["estimate"] = guard_estimate(X, faces, r, budget)
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--mesh", default="suzanne", choices=["suzanne", "grid", "tri35k"])
    ap.add_argument("--budget", type=float, default=2e9,
                    help="memory_budget in bytes (default: BlendingSurface's default, 2e9)")
    ap.add_argument("--child", nargs=2, metavar=("STAGE", "TRACE"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(args.mesh, args.points, args.child[0], args.child[1] == "1",
                               args.budget)))
        return 0
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    rows = []
    stages = ("stencil", "tessellate", "build")
    for stage in stages:
        for trace in ("0", "1"):
            cmd = [sys.executable, __file__, "--points", str(args.points), "--mesh", args.mesh,
                   "--budget", str(args.budget), "--child", stage, trace]
            out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
            rows.append(json.loads(out.strip().splitlines()[-1]))
    mb = lambda b: f"{b / 1e6:8.0f} MB"  # noqa: E731
    first = rows[0]
    print(f"mesh {first['mesh']}: resolution {first['resolution']}, {first['points']} points, "
          f"{first['triangles']} triangles")
    for stage in stages:
        rss = next(r for r in rows if r["stage"] == stage and "rss_peak_total" in r)
        tm = next(r for r in rows if r["stage"] == stage and "tracemalloc_peak" in r)
        print(f"{stage:>10}: estimate {mb(rss['estimate'])} | tracemalloc peak "
              f"{mb(tm['tracemalloc_peak'])} (ratio estimate/peak "
              f"{rss['estimate'] / tm['tracemalloc_peak']:.2f}) | RSS peak "
              f"{mb(rss['rss_peak_total'])} total, {mb(rss['rss_peak_above_start'])} above the {mb(rss['rss_start'])} at start"
              f" | {rss['seconds']:.1f} s, finite {rss['finite']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
