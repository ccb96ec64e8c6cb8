"""The inputs of bench_shape: meshes (V, F) with the exact surface their vertices lie on.

Every input is a :class:`Case`; ``build_cases(bpy, names, notes)`` makes the named
ones (in :data:`ORDER`), appending a line to ``notes`` for every mesh skipped or
cleaned. Groups: ``sphere`` (icosphere levels 1-4 on the unit sphere), ``torus``
(R = 1, r = 0.4, quads 12x8 ... 48x32 sampled exactly), ``heightfield`` (z = f(x, y)
of :meth:`HeightField.wave` on [-1, 1]^2: a jittered quad grid and a triangle grid,
both with boundary), ``blender`` (Blender's primitives with default parameters,
read from bpy.ops.mesh.primitive_*_add; Cylinder and Cone also at 2 r) and
``real`` (examples/suzanne.obj and MeshLab's sample meshes); not in the default run:
``proportions`` (the Cylinder as a coin, a tower, with loop cuts; the Cube scaled to a
board and a plank), ``bevel``
(Blender's Cube with its Bevel modifier applied) and ``extrusions`` (an extruded L-shaped
slab, an inset-and-extruded Cube).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gerbs_core.datasets import primitives
from gerbs_core.errors import InvalidMeshError
from gerbs_core.mesh import MeshTopology, validate_geometry
from gerbs_core.datasets.obj import read_obj
from gerbs_core.testing import HeightField, Torus, UnitSphere

ROOT = Path(__file__).resolve().parents[2]
TORUS = Torus(1.0, 0.4)
WAVE = HeightField.wave()
TORUS_SIZES = ((12, 8), (24, 16), (48, 32))
# Blender primitive -> (operator, the exact surface its default vertices lie on, or None)
BLENDER = {"cube": ("primitive_cube_add", None), "cylinder": ("primitive_cylinder_add", None),
           "cone": ("primitive_cone_add", None), "uvsphere": ("primitive_uv_sphere_add", UnitSphere()),
           "btorus": ("primitive_torus_add", Torus(1.0, 0.25)), "monkey": ("primitive_monkey_add", None)}
# Blender's Cylinder in other proportions (not in the default run: ``--only proportions``):
# name -> (operator keyword arguments, loop cuts along its height). Subdivision is affine
# invariant, so the peers' box ratios are the default Cylinder's at every proportion;
# GERBS's local functions are not (docs/design.md, "Known limits")
PROPORTIONS = {"coin": ({"depth": 0.2}, 0), "tower": ({"depth": 10.0}, 0),
               "cylinder-cuts": ({}, 3)}
# Blender's Cube scaled as a modeller makes a board or a plank (Object > Apply > Scale):
# name -> the scale of its x, y, z (not in the default run: ``--only proportions``)
SCALED_CUBES = {"board": (1.0, 1.0, 0.1), "plank": (2.0, 0.25, 0.1)}
# Blender's Cube with its Bevel modifier applied, as a modeller rounds a box's edges before
# subdividing (not in the default run, nor in the acceptance: ``--only bevel``): name ->
# (segments, width). Every edge of such a cage turns 90 / segments degrees, below the
# tension's sharpness (docs/design.md, "Known limits")
BEVELS = {"bevel1": (1, 0.2), "bevel2": (2, 0.2), "bevel4": (4, 0.2), "bevel2-thin": (2, 0.05)}
# extruded shapes as a modeller makes them (not in the default run, nor in the acceptance:
# ``--only extrusions``): an L-shaped hexagon (2 x 2, a 1 x 1 notch) extruded 0.5 (a slab
# with n-gon caps, like the coin), the same with support loops (caps inset by 0.05, the
# sides cut 0.06 from either cap), and the Cube with its top face inset by 0.3 and the
# inset extruded 0.6 up
EXTRUSIONS = ("l-slab", "l-slab-loops", "inset-tower")
SAMPLES = "pymeshlab/tests/sample_meshes"
REAL = {"suzanne": ROOT / "examples" / "suzanne.obj", "cow": "cow.obj", "airplane": "airplane.obj",
        "bone": "bone.ply", "bunny10k": "bunny10k_textured.obj"}
GROUPS = {
    "sphere": [f"ico{k}" for k in (1, 2, 3, 4)],
    "torus": [f"torus{a}x{b}" for a, b in TORUS_SIZES],
    "heightfield": ["hf-quad", "hf-tri"],
    "blender": ["cube", "cylinder", "cylinder@16", "cone", "cone@16", "uvsphere", "btorus", "monkey"],
    "real": list(REAL),
    "proportions": list(PROPORTIONS) + list(SCALED_CUBES),
    "bevel": list(BEVELS),
    "extrusions": list(EXTRUSIONS),
}
ORDER = [n for g in GROUPS.values() for n in g]
# the default run: everything but bunny10k (about a minute more; --only bunny10k or real)
# and the groups of known limits
EXTRA_GROUPS = ("proportions", "bevel", "extrusions")
DEFAULT = [n for n in ORDER if n != "bunny10k"
           and not any(n in GROUPS[g] for g in EXTRA_GROUPS)]
QUICK = ["ico1", "ico2", "ico3", "torus12x8", "torus24x16", "hf-quad", "hf-tri", "cube",
         "cylinder", "cylinder@16", "cone", "cone@16", "suzanne"]
# refinement sequences whose observed orders are reported: name -> members
SEQUENCES = {"ico L2-4": ["ico2", "ico3", "ico4"], "torus 12-48": GROUPS["torus"]}


@dataclass
class Case:
    """One input: cage (V (V,3), F list of int tuples or (F,k) array), the exact
    surface (with ``closest``) or None, the resolution factor (1: r, 2: 2r), the
    group, whether GERBS's exact derivatives are evaluated, and ``margin``: output
    points closer than this (in x, y) to the domain's boundary are left out of the
    curvature statistics (height fields)."""

    name: str
    V: np.ndarray
    F: object
    group: str
    exact: object = None
    scale: int = 1
    derivatives: bool = True
    margin: float = 0.0
    info: dict = field(default_factory=dict)

    @property
    def h(self) -> float:
        """Mean edge length of the cage (the mesh size of the refinement orders)."""
        t = MeshTopology(self.F, len(self.V))
        e = np.asarray(t.edges)
        return float(np.linalg.norm(self.V[e[:, 0]] - self.V[e[:, 1]], axis=1).mean())


def expand(names):
    """Input names (group names expand to their members), in :data:`ORDER`."""
    want = set()
    for n in names:
        if n in GROUPS:
            want.update(GROUPS[n])
        elif n in ORDER:
            want.add(n)
        else:
            raise SystemExit(f"unknown input {n!r}; inputs: {', '.join(ORDER)}; groups: "
                             f"{', '.join(GROUPS)}")
    return [n for n in ORDER if n in want]


def height_field_mesh(kind: str, n: int = 12, seed: int = 7):
    """n x n cells on [-1, 1]^2, z = f(x, y). ``quad``: interior vertices jittered by
    up to 0.25 cells in x and y; ``tri``: the regular triangle grid (valence 6)."""
    V, F = primitives.grid(n, n, kind="quad" if kind == "quad" else "tri", size=2.0)
    V = V - [1.0, 1.0, 0.0]
    if kind == "quad":
        inner = np.all(np.abs(V[:, :2]) < 1 - 1e-9, axis=1)
        jit = np.random.default_rng(seed).uniform(-0.25, 0.25, (int(inner.sum()), 2)) * (2.0 / n)
        V[inner, :2] += jit
    V[:, 2] = WAVE.height(V[:, 0], V[:, 1])
    return V, F


def blender_primitive(bpy, op: str, cuts: int = 0, **params):
    """(V, faces) of a Blender primitive added with default parameters (or ``params``),
    the faces in Blender's order -- except the UV sphere's, which Blender emits in a
    different order at every call (bpy 5.0.1): those are sorted by their vertex sets
    (corner order kept), since the GERBS surface depends on the face order. ``cuts``:
    that many loop cuts across the vertical edges (a Cylinder's sides in cuts + 1 rows)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    getattr(bpy.ops.mesh, op)(**params)
    me = bpy.context.active_object.data
    if cuts:
        import bmesh
        bm = bmesh.new()
        bm.from_mesh(me)
        vertical = [e for e in bm.edges
                    if abs(e.verts[0].co.z - e.verts[1].co.z) > 1e-6]
        bmesh.ops.subdivide_edges(bm, edges=vertical, cuts=cuts, use_grid_fill=False)
        bm.to_mesh(me)
        bm.free()
    V, faces = _mesh_arrays(me)
    if op == "primitive_uv_sphere_add":
        faces.sort(key=sorted)
    return V, faces


def _mesh_arrays(me):
    """(V (V, 3) float64, faces [tuple of vertex indices]) of a bpy mesh."""
    V = np.empty(3 * len(me.vertices))
    me.vertices.foreach_get("co", V)
    return V.reshape(-1, 3), [tuple(p.vertices) for p in me.polygons]


def bevelled_cube(bpy, segments: int, width: float):
    """(V, faces) of Blender's default Cube with a Bevel modifier (``segments``, ``width``,
    Blender's other defaults: every edge, profile 0.5) applied: the evaluated mesh."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add()
    ob = bpy.context.active_object
    mod = ob.modifiers.new("bevel", "BEVEL")
    mod.segments, mod.width = segments, width
    ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    try:
        return _mesh_arrays(ev.to_mesh())
    finally:
        ev.to_mesh_clear()


def extruded(bpy, name: str):
    """(V, faces) of an input of :data:`EXTRUSIONS`, made with bmesh as the Extrude and
    Inset tools make it (outward normals)."""
    import bmesh

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bm = bmesh.new()
    try:
        if name.startswith("l-slab"):
            pts = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
            cap = bm.faces.new([bm.verts.new((x, y, 0.0)) for x, y in pts])
            up = bmesh.ops.extrude_face_region(bm, geom=[cap])
            bmesh.ops.translate(bm, verts=[e for e in up["geom"] if isinstance(e, bmesh.types.BMVert)],
                                vec=(0.0, 0.0, 0.5))
            if name == "l-slab-loops":
                bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
                caps = [f for f in bm.faces if abs(f.normal.z) > 0.9]
                bmesh.ops.inset_individual(bm, faces=caps, thickness=0.05)
                for z in (0.06, 0.44):
                    bmesh.ops.bisect_plane(bm, geom=list(bm.verts) + list(bm.edges) + list(bm.faces),
                                           plane_co=(0.0, 0.0, z), plane_no=(0.0, 0.0, 1.0))
        else:
            bmesh.ops.create_cube(bm, size=2.0)
            top = [f for f in bm.faces if f.normal.z > 0.5]
            bmesh.ops.inset_region(bm, faces=top, thickness=0.3)
            inner = [f for f in bm.faces if f.normal.z > 0.5
                     and abs(f.calc_center_median().x) < 1e-6 and abs(f.calc_center_median().y) < 1e-6]
            up = bmesh.ops.extrude_face_region(bm, geom=inner)
            bmesh.ops.delete(bm, geom=inner, context="FACES")
            bmesh.ops.translate(bm, verts=[e for e in up["geom"] if isinstance(e, bmesh.types.BMVert)],
                                vec=(0.0, 0.0, 0.6))
        bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
        V = np.array([v.co[:] for v in bm.verts], dtype=np.float64)
        bm.verts.index_update()
        faces = [tuple(v.index for v in f.verts) for f in bm.faces]
    finally:
        bm.free()
    return V, faces


def sample_path(name: str) -> Path:
    import pymeshlab
    return Path(pymeshlab.__file__).resolve().parent / "tests" / "sample_meshes" / name


def load_real(name: str, notes: list):
    """(V, F) of a real mesh, or None (reason appended to ``notes``). OBJ through the
    core's reader (polygons kept), PLY through MeshLab. Unreferenced vertices, which
    the core refuses and which carry no surface, are removed (said in ``notes``);
    any other refusal of the core skips the mesh."""
    src = REAL[name]
    path = src if isinstance(src, Path) else sample_path(src)
    if path.suffix == ".obj":
        V, F = read_obj(str(path))
    else:
        import pymeshlab
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))
        V, F = ms.current_mesh().vertex_matrix(), [tuple(f) for f in ms.current_mesh().face_matrix()]
    V = np.asarray(V, dtype=np.float64)
    used = np.zeros(len(V), dtype=bool)
    used[np.concatenate([np.asarray(f) for f in F])] = True
    where = path.name if isinstance(src, Path) else f"{SAMPLES}/{src}"
    if not used.all():
        remap = np.cumsum(used) - 1
        notes.append(f"{name} ({where}): {int((~used).sum())} unreferenced vertices removed "
                     f"(the core refuses them; MeshLab's 'Remove Unreferenced Vertices')")
        V, F = V[used], [tuple(remap[list(f)]) for f in F]
    try:
        topo = MeshTopology(F, len(V))
        validate_geometry(V, topo)
    except InvalidMeshError as exc:
        notes.append(f"{name} ({where}): SKIPPED, refused by the core: {exc}")
        return None
    nb = int(np.sum(topo.edge_is_boundary))
    sizes = np.bincount(np.asarray(topo.face_sizes))
    kinds = ", ".join(f"{c} {k}-gons" for k, c in enumerate(sizes) if c)
    notes.append(f"{name} ({where}): {len(V)} vertices, {kinds}; manifold, "
                 f"{'closed' if nb == 0 else f'{nb} boundary edges'}")
    return V, F


def build_cases(bpy, names, notes):
    """The :class:`Case` of every name (see :func:`expand`), skipping refused meshes."""
    out = []
    cache = {}
    for name in names:
        base, _, at = name.partition("@")
        scale = 2 if at else 1
        if name.startswith("ico"):
            V, F = primitives.icosphere(int(name[3:]))
            out.append(Case(name, V, F, "sphere", UnitSphere()))
        elif name.startswith("torus"):
            a, b = map(int, name[5:].split("x"))
            V, F = TORUS.sample(a, b)
            out.append(Case(name, V, F, "torus", TORUS))
        elif name.startswith("hf-"):
            V, F = height_field_mesh(name[3:])
            out.append(Case(name, V, F, "heightfield", WAVE, margin=2.0 / 12))
        elif base in PROPORTIONS:
            params, cuts = PROPORTIONS[base]
            V, F = blender_primitive(bpy, "primitive_cylinder_add", cuts, **params)
            out.append(Case(name, V, F, "proportions", None))
        elif base in SCALED_CUBES:
            V, F = blender_primitive(bpy, "primitive_cube_add")
            out.append(Case(name, V * np.array(SCALED_CUBES[base]), F, "proportions", None))
        elif base in BEVELS:
            V, F = bevelled_cube(bpy, *BEVELS[base])
            out.append(Case(name, V, F, "bevel", None))
        elif base in EXTRUSIONS:
            V, F = extruded(bpy, base)
            out.append(Case(name, V, F, "extrusions", None))
        elif base in BLENDER:
            op, exact = BLENDER[base]
            if base not in cache:
                cache[base] = blender_primitive(bpy, op)
            V, F = cache[base]
            # Blender stores float32 (and its sin/cos): 1e-6 off the exact surface
            if exact is not None and np.abs(exact.closest(V)[0]).max() > 1e-5:
                notes.append(f"{base}: vertices are not on {exact}; no exact surface")
                exact = None
            out.append(Case(name, V, F, "blender", exact, scale=scale))
        else:
            got = load_real(name, notes)
            if got is not None:
                out.append(Case(name, *got, "real", None, derivatives=False))
    return out
