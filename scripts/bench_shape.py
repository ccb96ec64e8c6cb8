#!/usr/bin/env python
"""Shape of GERBS against subdivision on the same inputs (issue 11, deliverable 1).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python scripts/bench_shape.py [--quick]
        [--only NAME,...] [--variant a,b,c] [--resolution 8]

Methods, at matched output density (GERBS resolution r = 2^L against L steps):
Modified Butterfly and Loop (MeshLab's filters through pymeshlab, on the cage
fan-triangulated: quads split along the diagonal 0-2, n-gons into a fan from
their first corner; edge threshold 0, so every edge is split at every step),
Catmull-Clark (Blender's Subdivision Surface modifier, Blender's defaults, the
evaluated mesh) and the GERBS variants. Inputs (``--only`` takes names or the
groups sphere, torus, heightfield, blender, real, proportions, bevel, extrusions): icosphere levels 1-4 on the
unit sphere; the torus R = 1, r = 0.4 as exact quad meshes 12x8, 24x16, 48x32;
z = f(x, y) on a jittered quad grid and a triangle grid (curvature statistics
leave out points within one cell of the boundary); Blender's Cube, Cylinder,
Cone, UV Sphere, Torus and Monkey with default parameters (Cylinder and Cone
also at 2r: the "@16" rows); real meshes (examples/suzanne.obj, MeshLab's cow,
airplane, bone, and bunny10k with ``--only bunny10k`` or ``--only real``: it
adds about a minute; also Catmull-Clark level 2 there, the acceptance's
reference); with ``--only proportions``, Blender's Cylinder as a coin (depth 0.2), a
tower (depth 10) and with three loop cuts, and Blender's Cube scaled to a 2 x 2 x 0.2 board
and a 4 x 0.5 x 0.2 plank, with ``--only bevel`` Blender's Cube with its
Bevel modifier applied (1, 2 and 4 segments of width 0.2, and 2 of width 0.05), with
``--only extrusions`` an L-shaped slab extruded 0.5 and the Cube with an inset top extruded
(none of these groups in the default run, nor in the acceptance: GERBS's known limits,
docs/design.md). See scripts/shape/measure.py for every figure and the verdict block
for the acceptance of issue 11. ``--quick``: a subset (no level-4 sphere, no
48x32 torus, no real mesh but Suzanne).

GERBS variants (``--variant a,b,c``, default "default"), measured side by side:
  * a name of the registry ``VARIANTS`` in scripts/shape/methods.py (name ->
    keyword options of gerbs_core.BlendingSurface); every GERBS access goes
    through ``gerbs_samples(V, F, r, exact=True, **options)`` there, the one
    function to change when the core's API changes;
  * ``path/to/file.py:function`` or ``package.module:function``: a prototype
    callable f(V, F, r) (optionally with an ``exact=`` keyword: False means H_exact
    is not needed) returning dict(points (P,3), triangles (T,3), normals (P,3) or
    None, H_exact (P,) or None), measured like the registry variants, with no
    change to this script. From Python: ``run(names, {"label": f, ...})``.
"""
from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bpy  # noqa: E402,F401  (before pymeshlab: their bundled libraries clash otherwise)
import pymeshlab  # noqa: E402,F401

import numpy as np  # noqa: E402

from shape import inputs, methods, report  # noqa: E402
from shape.measure import measure, orders  # noqa: E402


def header(r, variants):
    from importlib.metadata import version
    import scipy
    return [f"# bench_shape {datetime.date.today().isoformat()}: bpy {bpy.app.version_string}, "
            f"pymeshlab {version('pymeshlab')}, numpy {np.__version__}, scipy {scipy.__version__}",
            f"resolution r = {r} (peers: L = {int(np.log2(r))} steps), '@16' rows at 2r; GERBS "
            f"variants: " + "; ".join(f"{k} = {v}" for k, v in variants.items())]


def run_case(case, method_list, r, results, timing, log):
    for label, f in method_list:
        t = time.perf_counter()
        try:
            out = f(case.V, case.F, r * case.scale, exact=case.derivatives)
            results[(case.name, label)] = measure(case, out)
        except Exception as exc:  # one failing method must not hide the others' figures
            log.append(f"{case.name} / {label}: FAILED: {type(exc).__name__}: {exc}")
        timing[label] = timing.get(label, 0.0) + time.perf_counter() - t


NOTES = [
    "- peers on triangle meshes: quads split along the diagonal 0-2, n-gons fan-triangulated "
    "from their first corner (MeshLab needs triangles); MeshLab edge threshold 0; "
    "Catmull-Clark: Blender defaults (limit surface, boundary smooth ALL, quality 3) on the "
    "polygons",
    "- n° max: output's angle-weighted vertex normals; nx° max: the method's own normals "
    "(GERBS: exact derivatives); H: cotangent (Meyer et al.) at interior vertices; Hx: exact "
    "derivatives (GERBS; not on the real meshes, for time); hf-*: curvature over points >= 1 "
    "cell from the boundary, distances and normals over all",
    "- box x/y/z: output box extent / cage box extent; >60/>90/max°: adjacent output triangle "
    "pairs whose normals differ by more than 60 / 90 degrees, the largest angle; (xq): largest "
    "angle at 2r over that at r; 'order' rows: observed order (least-squares slope of log "
    "figure vs log mean cage edge length)",
    "- zebra: the pieces the zebra stripes break into per environment direction, those "
    "covering at least 1e-3 / 1e-4 of the area (the zebra shader's default stripe density, 24 directions, the "
    "output's vertex normals; gerbs_core.testing.stripe_components): fewer is fairer at the "
    "same output count; a fair sphere 18/18",
]


def derived(cases, labels, results):
    """(ratios {(2r input, method): largest dihedral at 2r / at r}, observed orders
    {sequence: {method: {figure: order}}})."""
    ratios = {}
    for c in cases:
        base = c.name.partition("@")[0]
        for m in labels:
            if c.scale == 2 and (c.name, m) in results and (base, m) in results:
                ratios[(c.name, m)] = results[(c.name, m)]["fmax"] / results[(base, m)]["fmax"]
    by_name = {c.name: c for c in cases}
    ords = {}
    for seq, members in inputs.SEQUENCES.items():
        if all(n in by_name for n in members):
            ords[seq] = {m: orders([by_name[n] for n in members], [results[(n, m)] for n in members])
                         for m in labels if all((n, m) in results for n in members)}
    return ratios, ords


def run(names, variants, r=8, progress=True):
    """Measure every method on the inputs ``names`` (see ``--only``); ``variants``
    {label: f(V, F, r) or f(V, F, r, exact=...) -> output dict}. Returns (lines of
    the report after the header, results {(input, method): figures})."""
    variants = {k: methods.as_variant(f) for k, f in variants.items()}
    notes, log, results, timing = [], [], {}, {}
    cases = inputs.build_cases(bpy, inputs.expand(names), notes)
    labels = []
    for case in cases:
        t = time.perf_counter()
        ml = methods.peers(bpy, real=case.group == "real" or case.name == "monkey")
        ml += list(variants.items())
        labels += [m for m, _ in ml if m not in labels]
        run_case(case, ml, r, results, timing, log)
        if progress:
            print(f"  {case.name}: {time.perf_counter() - t:.1f} s", file=sys.stderr, flush=True)
    ratios, ords = derived(cases, labels, results)
    lines = ["", *report.table(cases, labels, results, ords, ratios), "", "Notes:", *NOTES]
    lines += [f"- {n}" for n in notes + log]
    bad = [f"{k[0]}/{k[1]}: {v['orient']}" for k, v in results.items() if v["orient"]]
    if bad:
        lines.append("- orientation defects (signs unreliable): " + ", ".join(bad))
    lines += ["", "Acceptance (issue 11; PASS/FAIL per GERBS variant):"]
    for g in variants:
        lines.append(f"{g}:")
        lines += ["  " + s for s in report.Verdicts(results, ords, ratios, g).all()]
    lines += ["", "time per method (s): " + ", ".join(f"{k} {v:.1f}" for k, v in timing.items())]
    return lines, results


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a subset of the inputs")
    ap.add_argument("--only", default=None, help="comma-separated input or group names")
    ap.add_argument("--variant", default="default",
                    help=f"comma-separated GERBS variants: {', '.join(methods.VARIANTS)} or "
                         f"file.py:function / module:function")
    ap.add_argument("--resolution", type=int, default=8, help="r (a power of 2; default 8)")
    args = ap.parse_args(argv)
    r = args.resolution
    if r < 2 or r & (r - 1):
        ap.error("--resolution must be a power of 2 (matched subdivision levels)")
    names = (args.only.split(",") if args.only else inputs.QUICK if args.quick else inputs.DEFAULT)
    variants = dict(methods.resolve_variant(s) for s in args.variant.split(","))
    shown = {k: methods.VARIANTS.get(k, "callable") for k in variants}
    t0 = time.perf_counter()
    lines, _ = run(names, variants, r)
    print("\n".join(header(r, shown) + lines))
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
