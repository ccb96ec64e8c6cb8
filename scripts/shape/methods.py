"""The methods bench_shape compares, each (V, F, level L or resolution r) -> output dict

    {"points": (P, 3), "triangles": (T, 3), "normals": (P, 3) or None,
     "H_exact": (P,) or None}

(normals None: the measurement uses angle-weighted vertex normals of the output).

Peers: Modified Butterfly and Loop (MeshLab through pymeshlab, L iterations on the
fan-triangulated cage, edge threshold 0 so that every edge is split at every
step) and Catmull-Clark (Blender's Subdivision Surface modifier at level L with
Blender's defaults, the evaluated mesh's positions and loop triangles).

GERBS: every access goes through :func:`gerbs_samples`, the one place written
against the core's API. A variant is a registry entry (name -> keyword options
of that adapter) or any callable f(V, F, r) -> output dict (see
:func:`resolve_variant`).
"""
from __future__ import annotations

import contextlib
import importlib
import importlib.util
from pathlib import Path

import numpy as np

import gerbs_core
from gerbs_core.mesh import spoke_caps
from gerbs_core.testing import mean_curvature_from_derivatives

# GERBS configurations measured side by side (--variant a,b,c): name -> options.
# The default and the designs it was chosen against (docs/design.md): each leaves out
# one ingredient of the fair-shape rule (gerbs_core.mesh.agreement).
VARIANTS = {
    "default": {},
    "degree-2": {"fairness": gerbs_core.FairnessRule(candidates=((2, 1),), sweeps=0)},
    "choice-only": {"fairness": gerbs_core.FairnessRule(sweeps=0)},
    "no-tension": {"fairness": gerbs_core.FairnessRule(lam=0.0)},
    "fixed-degree-2": {"fairness": gerbs_core.FairnessRule(candidates=((2, 1),))},
    "no-fold": {"fairness": gerbs_core.FairnessRule(fold=0.0)},
    # the default before the fold penalty and the resolution-3 energies (2026-12-01)
    "former": {"fairness": gerbs_core.FairnessRule(fold=0.0, resolution=4)},
    "energy-res-3": {"fairness": gerbs_core.FairnessRule(resolution=3)},
    "energy-res-5": {"fairness": gerbs_core.FairnessRule(resolution=5)},
    # star covers without the spoke caps of sliver fans (gerbs_core.mesh.spoke_caps)
    "no-caps": {"spoke_caps": False},
    # without the extra candidate at spread stars (gerbs_core.mesh.spread_fits)
    "no-spread": {"fairness": gerbs_core.FairnessRule(spread=180.0)},
    # the coupling's agreement as strong at spread stars as elsewhere (the default
    # until 2026-12-04; gerbs_core.mesh.agreement.row_mu)
    "no-spread-mu": {"fairness": gerbs_core.FairnessRule(spread_mu=1.0)},
    # without the fairing of the surface's turns (gerbs_core.mesh.fairing; the default
    # until 2026-12-06)
    "no-fairing": {"fairness": gerbs_core.FairnessRule(turn=180.0)},
    # the fairing without its stay (the default until 2026-12-07)
    "no-stay": {"fairness": gerbs_core.FairnessRule(turn_stay=0.0)},
}


def gerbs_samples(V, F, r, exact=True, **options):
    """GERBS surface of the cage (V (V,3), F faces) sampled at resolution r.

    options: keyword arguments of gerbs_core.BlendingSurface, and ``spoke_caps=False``
    (covers without :mod:`gerbs_core.mesh.spoke_caps`). exact: also the
    mean curvature from the exact first and second derivatives (else None).
    Returns the output dict of this module; the mesh vertices are the samples
    ``lat.vertex_sample``, the normals dS/dx1 x dS/dx2 normalised.
    """
    caps = options.pop("spoke_caps", True)
    with contextlib.nullcontext() if caps else spoke_caps.disabled():
        s = gerbs_core.BlendingSurface(V, F, **options)
    if not exact:
        P, T, N = s.tessellate(r)
        return {"points": P, "triangles": np.asarray(T), "normals": N, "H_exact": None}
    lat = s.lattice(r)
    x = lat.map_to_polygon(s.layouts.corners)
    S, dS, d2S = s.evaluate_all(lat.face, x, nu=2)  # dS (P,3,2), d2S (P,3,2,2), face-local
    # at a mesh vertex the face coordinates are singular (the angle-scaled chart is
    # not differentiable at its centre); there S = l_v o zeta_v, so the derivatives
    # of l_v at y = 0 in chart coordinates give the same geometry
    vs = np.asarray(lat.vertex_sample)
    for v, p in enumerate(vs):
        _, dS[p], d2S[p] = (a[0] for a in s.local_function(v, np.zeros((1, 2)), nu=2))
    n = np.cross(dS[..., 0], dS[..., 1])
    ln = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, ln, out=np.full_like(n, np.nan), where=ln > 0)
    return {"points": S, "triangles": np.asarray(lat.triangles), "normals": n,
            "H_exact": mean_curvature_from_derivatives(dS, d2S)}


def resolve_variant(spec: str):
    """(label, f(V, F, r, exact) -> output dict) of a --variant entry: a name of
    :data:`VARIANTS`, or ``path/to/file.py:function`` / ``package.module:function``
    naming a callable f(V, F, r) (it may take ``exact=`` too; its H_exact may be None)."""
    if spec in VARIANTS:
        opts = VARIANTS[spec]
        return spec, lambda V, F, r, exact=True: gerbs_samples(V, F, r, exact=exact, **opts)
    if ":" not in spec:
        raise SystemExit(f"unknown variant {spec!r}: one of {', '.join(VARIANTS)} or "
                         f"file.py:function / module:function")
    where, func = spec.rsplit(":", 1)
    if where.endswith(".py"):
        path = Path(where).resolve()
        sp = importlib.util.spec_from_file_location(path.stem, path)
        mod = importlib.util.module_from_spec(sp)
        sp.loader.exec_module(mod)
    else:
        mod = importlib.import_module(where)
    return f"{Path(where).stem}:{func}", as_variant(getattr(mod, func))


def as_variant(f):
    """Wrap a prototype f(V, F, r) [-> output dict] so it takes ``exact=`` too and
    its dict has every key (normals and H_exact default to None)."""
    import inspect
    takes_exact = "exact" in inspect.signature(f).parameters

    def run(V, F, r, exact=True):
        out = f(V, F, r, exact=exact) if takes_exact else f(V, F, r)
        return {"normals": None, "H_exact": None, **out}
    return run


def fan_triangles(F):
    """(T, 3): every face split into the fan (0, k, k+1) from its first corner: a quad
    along its diagonal 0-2, an n-gon into n - 2 triangles."""
    return np.array([(f[0], f[k], f[k + 1]) for f in F for k in range(1, len(f) - 1)],
                    dtype=np.int64)


def meshlab(V, F, kind: str, L: int):
    """MeshLab's Modified Butterfly (kind "butterfly") or Loop ("loop"), L steps."""
    import pymeshlab
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.asarray(V, dtype=np.float64), fan_triangles(F)))
    filt = getattr(ms, f"meshing_surface_subdivision_{kind}")
    filt(iterations=L, threshold=pymeshlab.PercentageValue(0.0))
    m = ms.current_mesh()
    return {"points": m.vertex_matrix().astype(np.float64), "triangles": m.face_matrix().astype(np.int64),
            "normals": None, "H_exact": None}


def catmull_clark(bpy, V, F, L: int):
    """Blender's Subdivision Surface modifier (Catmull-Clark, defaults) at level L."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    me = bpy.data.meshes.new("cage")
    me.from_pydata([tuple(map(float, v)) for v in V], [], [tuple(int(i) for i in f) for f in F])
    me.update()
    ob = bpy.data.objects.new("cage", me)
    bpy.context.scene.collection.objects.link(ob)
    mod = ob.modifiers.new("subsurf", "SUBSURF")
    mod.levels = mod.render_levels = L
    dg = bpy.context.evaluated_depsgraph_get()
    dg.update()
    ev = ob.evaluated_get(dg)
    out = ev.to_mesh()
    try:
        out.calc_loop_triangles()
        P = np.empty(3 * len(out.vertices))
        out.vertices.foreach_get("co", P)
        T = np.empty(3 * len(out.loop_triangles), dtype=np.int64)
        out.loop_triangles.foreach_get("vertices", T)
    finally:
        ev.to_mesh_clear()
    return {"points": P.reshape(-1, 3), "triangles": T.reshape(-1, 3), "normals": None,
            "H_exact": None}


def peers(bpy, real: bool):
    """[(label, f(V, F, r, exact) -> output dict)] of the peers at level L = log2 r
    (``exact`` is ignored: they have no exact derivatives); ``real`` adds
    Catmull-Clark at level 2 (the acceptance's reference on real meshes)."""
    lvl = lambda r: int(round(np.log2(r)))  # noqa: E731
    out = [("butterfly", lambda V, F, r, exact=False: meshlab(V, F, "butterfly", lvl(r))),
           ("loop", lambda V, F, r, exact=False: meshlab(V, F, "loop", lvl(r))),
           ("catmull-clark", lambda V, F, r, exact=False: catmull_clark(bpy, V, F, lvl(r)))]
    if real:
        out.append(("catmull-clark L2",
                    lambda V, F, r, exact=False: catmull_clark(bpy, V, F, 2)))
    return out
