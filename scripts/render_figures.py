"""Render the README figures from the real code into docs/img/ (PNG).

    python scripts/render_figures.py [--out docs/img] [--size 800x600] [--samples 24]
                                     [--only NAME ...] [--quick]

Blender figures (real ``bpy``, Cycles on the CPU; OpenImageDenoise when samples >= 4):
  suzanne, icosphere, mixed     control mesh (dark wire) over the GERBS blending surface
  zebra_subsurf                 reflection lines: GERBS | Blender Subdivision Surface (matched counts)
  zebra_kinked                  reflection lines: GERBS | exact (kinked) polygon gauge, with the
                                mesh edges drawn on the surface; second row: close-ups
  zebra_crease                  reflection lines: GERBS with one edge loop fully creased |
                                the same mesh without creases
  zebra_peers_suzanne, zebra_peers_torus, zebra_peers_cylinder, zebra_peers_coin,
  zebra_peers_bevel
                                reflection lines: GERBS | Modified Butterfly (MeshLab, pymeshlab)
                                | Catmull-Clark (Subdivision Surface), matched output density
Plots (matplotlib, Agg; the optional ``docs`` extra):
  kernels                       F and b of ERBS (several parameter sets), BFBS, logistic, affine, step
  partition                     partition of unity Psi_i on a Delaunay star-1 cover
  convergence                   scattered-data interpolation of Franke's F1, log-log

``--quick`` lowers tessellation resolutions and point counts (used by the test).
Every figure is built from gerbs_core objects (and scripts/bench_scattered.py for the
convergence plot); nothing is precomputed. About 3-4 minutes on 2 cores at the defaults,
plus about a minute per zebra_peers figure at the README's ``--size 600x400 --samples 8``
(they also need pymeshlab, the benchmark dependency, for Modified Butterfly).
"""
from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402

from figures import gerbs  # noqa: E402

BLENDER_FIGURES = ("suzanne", "icosphere", "mixed", "zebra_subsurf", "zebra_kinked",
                   "zebra_crease",
                   "zebra_peers_suzanne", "zebra_peers_torus", "zebra_peers_cylinder",
                   "zebra_peers_coin", "zebra_peers_bevel", "zebra_peers_board")
PLOT_FIGURES = ("kernels", "partition", "convergence")
ALL_FIGURES = BLENDER_FIGURES + PLOT_FIGURES


# ---------------------------------------------------------------- meshes


def _suzanne():
    from gerbs_core.datasets.primitives import suzanne

    v, f = suzanne()
    v = np.asarray(v, dtype=np.float64)
    # the OBJ is Y-up; Blender is Z-up (the OBJ importer's axis conversion)
    return np.stack([v[:, 0], -v[:, 2], v[:, 1]], 1), f


def _icosphere():
    from gerbs_core.datasets.primitives import icosphere

    return icosphere(1)


def _mixed():
    from gerbs_core.datasets.primitives import mixed_mesh

    return mixed_mesh(bend=1.6)


# name: (mesh, view direction, tessellation resolution (full, quick))
WIRE_SCENES = {
    "suzanne": (_suzanne, (0.75, -1.6, 0.55), (6, 2)),
    "icosphere": (_icosphere, (0.9, -1.5, 0.8), (12, 3)),
    "mixed": (_mixed, (0.35, -1.1, 1.25), (12, 3)),
}


def _icosahedron():
    from gerbs_core.datasets.primitives import icosphere

    return icosphere(0)


# Zebra pairs. zebra_subsurf: the GERBS lattice resolution is chosen so that its
# output count is closest to Catmull-Clark's at `level`. zebra_kinked: the coarsest
# closed triangle mesh, where the exact gauge's creases are largest (on a triangle
# mesh they lie on the edges); both halves carry the images of the mesh edges on
# the surface as thin red curves, to show where the stripes break.
ZEBRA_SCENES = {
    "zebra_subsurf": dict(mesh=_icosphere, view=(0.9, -1.5, 0.8), stripes=14.0, level=(3, 2)),
    "zebra_kinked": dict(mesh=_icosahedron, view=(0.9, -1.5, 0.8), stripes=22.0, resolution=(24, 6)),
}




def _creased_sphere():
    """A UV sphere (16 x 8) and its creases: the latitude loop above the equator, full."""
    from gerbs_core.datasets.primitives import uv_sphere

    v, f = uv_sphere(16, 8)
    loop = 1 + 16 * 2 + np.arange(16)
    return v, f, {(int(a), int(b)): 1.0 for a, b in zip(loop, np.roll(loop, -1))}


CREASE_SCENE = dict(mesh=_creased_sphere, view=(0.9, -1.5, 0.5), stripes=14.0, resolution=(24, 6))

def _torus():
    from gerbs_core.datasets.primitives import torus

    return torus(24, 16, 1.0, 0.4)


def _cylinder():
    from gerbs_core.datasets.primitives import cylinder

    return cylinder()


def _coin():
    from gerbs_core.datasets.primitives import cylinder

    return cylinder(depth=0.2)


def _board():
    """Blender's Cube scaled to a 2 x 2 x 0.2 board (the scale applied): a known limit
    (bench_shape's input ``board``)."""
    from gerbs_core.datasets.primitives import cube
    from shape.inputs import SCALED_CUBES

    v, f = cube()
    return v * np.array(SCALED_CUBES["board"]), f


def _bevel():
    """Blender's Cube with its Bevel modifier applied (2 segments, width 0.2): a known limit."""
    import bpy
    from shape.inputs import bevelled_cube

    v, f = bevelled_cube(bpy, 2, 0.2)
    return v, [list(x) for x in f]


# GERBS | Butterfly | Catmull-Clark, one camera: the peers at `level` steps (full, quick),
# GERBS at the resolution whose output count is closest to theirs (figures/peers.py)
PEER_SCENES = {
    "zebra_peers_suzanne": dict(mesh=_suzanne, view=(0.45, -1.6, 0.45), stripes=12.0, zoom=0.88),
    "zebra_peers_torus": dict(mesh=_torus, view=(0.5, -1.2, 1.3), stripes=12.0, zoom=0.95),
    "zebra_peers_cylinder": dict(mesh=_cylinder, view=(0.9, -1.5, 1.0), stripes=10.0, zoom=0.9),
    "zebra_peers_coin": dict(mesh=_coin, view=(1.0, -1.6, 0.45), stripes=10.0, zoom=0.9),
    "zebra_peers_bevel": dict(mesh=_bevel, view=(1.0, -1.5, 0.9), stripes=10.0, zoom=0.9),
    "zebra_peers_board": dict(mesh=_board, view=(1.0, -1.6, 0.6), stripes=10.0, zoom=0.9),
}
PEER_LEVEL = (3, 1)


# ---------------------------------------------------------------- Blender figures


class Renderer:
    def __init__(self, out: Path, width: int, height: int, samples: int, quick: bool):
        self.out, self.width, self.height = out, width, height
        self.samples, self.quick = samples, quick
        self.tmp = Path(tempfile.mkdtemp(prefix="gerbs_fig_"))

    def _scene(self, square=False):
        from figures import scene as sc

        w = self.height if square else self.width
        return sc.reset_scene(w, self.height, self.samples)

    def wire_figure(self, name: str):
        """Shaded GERBS surface with the control mesh composited on top (two passes).

        The surface interpolates the vertices, so on convex parts the straight
        control edges run inside it. Pass 1 renders the lit surface; pass 2
        renders only the wire, with film transparency, behind a holdout copy of
        the surface moved inwards along its normals by more than the edges'
        sag, so that front edges show and back edges stay hidden.
        """
        from figures import materials, meshes
        from figures import scene as sc

        make, view, (res_full, res_quick) = WIRE_SCENES[name]
        v, f = make()
        pts, tris, nrm = gerbs.tessellate(v, f, res_quick if self.quick else res_full)
        s = self._scene()
        sc.set_world(s, (0.93, 0.94, 0.96), 0.55, backdrop=(1.0, 1.0, 1.0))
        sc.add_sun((-0.6, 0.9, -0.6), strength=2.6)
        sc.add_sun((0.9, 0.3, -0.2), strength=0.5, name="Fill")
        center, radius = sc.bounding_sphere(pts)
        cam = sc.add_camera(s, center, radius, view, points=pts)
        surf = meshes.surface_object("GERBS", pts, tris, nrm, materials.surface())
        # pass 1: the lit surface
        shaded = sc.load_png(sc.render(s, self.tmp / f"{name}_surface.png"))
        # pass 2: the control mesh over a holdout, inward-offset copy of the surface
        wire = self._wire_pass(s, cam, center, v, f, pts, nrm, tris, (0.02, 0.02, 0.025),
                               width_px=1.1, hide=[surf], tag=name)
        return sc.save_png(sc.alpha_over(wire, shaded), self.out / f"{name}.png"), {
            "vertices": len(v), "faces": len(f), "points_out": len(pts), "triangles_out": len(tris)}

    def _zebra_half(self, tag, caption, make_object, view, center, radius, stripes, overlay=None):
        """Render one object of a zebra pair with a fixed camera; returns the image.

        overlay: optional (points, normals, edge curves) of the tessellation: the images
        of the mesh edges on the surface, drawn as thin red tubes.
        """
        from figures import materials, meshes
        from figures import scene as sc

        s = self._scene(square=True)  # a pair side by side is 2H x H
        sc.set_world(s, (0.8, 0.8, 0.8), 1.0)
        cam = sc.add_camera(s, center, radius, view, margin=1.12)
        sc.add_caption(s, cam, caption, materials.emission((0.0, 0.0, 0.0)), height_frac=0.045,
                       backing=materials.emission((0.8, 0.8, 0.8), name="CaptionBox"))
        # the environment's bands circle the camera's horizontal axis, tilted up a little
        side = np.cross(view, (0.0, 0.0, 1.0))
        mat = materials.zebra(stripes=stripes,
                              axis=tuple(side / np.linalg.norm(side) + (0.0, 0.0, 0.35)))
        obj = make_object(meshes)
        obj.data.materials.clear()
        obj.data.materials.append(mat)
        if overlay is not None:
            # the mesh edges' images ON the surface, lifted by one tube radius along the normal
            pts, nrm, curves = overlay
            r = 0.7 * sc.pixel_size(s, cam, center)
            lifted = pts + r * _unit(nrm)
            segs = np.stack([curves[:, :-1], curves[:, 1:]], -1).reshape(-1, 2)
            meshes.tube_object("EdgeCurves", lifted, segs, r, materials.emission((0.95, 0.08, 0.02)))
        return sc.load_png(sc.render(s, self.tmp / f"zebra_{tag}.png"))

    def _wire_pass(self, s, cam, center, v, f, pts, nrm, tris, colour, width_px, hide, tag):
        """RGBA render of the control mesh's front edges over a transparent film.

        The surface interpolates the vertices, so on convex parts the straight
        edges run inside it. A holdout copy of the surface, moved inwards along
        its normals by more than the edges' sag, hides the back edges while the
        front ones show; edges all of whose faces face away from the camera are
        left out (near the silhouette the holdout would not hide them).
        """
        from scipy.spatial import cKDTree

        from figures import materials, meshes
        from figures import scene as sc

        e = meshes.edge_array(f)
        sag = cKDTree(pts).query(0.5 * (v[e[:, 0]] + v[e[:, 1]]))[0].max()
        px = sc.pixel_size(s, cam, center)
        wire_r = width_px * px
        depth = 1.3 * sag + 4.0 * wire_r
        for o in hide:
            o.hide_render = True
        hold = meshes.surface_object("Holdout", pts - depth * _unit(nrm), tris)
        hold.is_holdout = True
        eye = np.array(cam.location)
        front = [face for face in f if _faces_camera(v, face, eye)]
        # vertex dots only where the surface faces the camera (pts[:V] are the vertices)
        seen = np.einsum("ij,ij->i", nrm[:len(v)], eye - v) > 0.0
        meshes.wire_object("Wire", v, front, wire_r, materials.emission(colour), dots=seen)
        s.cycles.samples = max(1, min(self.samples, 8))
        s.cycles.use_denoising = False
        return sc.load_png(sc.render(s, self.tmp / f"{tag}_wire.png", transparent=True))

    def zebra_pair(self, name: str):
        from figures import meshes
        from figures import scene as sc

        spec = ZEBRA_SCENES[name]
        v, f = spec["mesh"]()
        view, stripes = spec["view"], spec["stripes"]
        info = {}
        if "level" in spec:
            level = spec["level"][1 if self.quick else 0]
            self._scene()
            sub_count = meshes.evaluated_counts(meshes.subsurf_object("probe", v, f, level))
            res = min(range(2, 40), key=lambda r: abs(gerbs.output_count(f, len(v), r) - sub_count[0]))
        else:
            res = spec["resolution"][1 if self.quick else 0]
        pts, tris, cn, nrm, jump, curves = gerbs.tessellate_split(v, f, res)
        center, radius = sc.bounding_sphere(pts)
        info.update(resolution=res, gerbs_points=len(pts), gerbs_triangles=len(tris),
                    gerbs_normal_jump_deg=float(f"{jump:.2g}"))
        overlay = None if "level" in spec else (pts, nrm, curves)
        left = self._zebra_half("gerbs", "GERBS", lambda m: m.surface_object("GERBS", pts, tris, cn),
                                view, center, radius, stripes, overlay)
        if "level" in spec:
            right = self._zebra_half(
                "subsurf", f"Subdivision Surface, level {level}",
                lambda m: m.subsurf_object("Subsurf", v, f, level), view, center, radius, stripes)
            info.update(subsurf_level=level, subsurf_points=sub_count[0], subsurf_triangles=sub_count[1])
        else:
            kp, kt, kcn, knrm, kjump, kcurves = gerbs.tessellate_split(v, f, res, kinked=True)
            make_kinked = lambda m: m.surface_object("Kinked", kp, kt, kcn)  # noqa: E731
            right = self._zebra_half("kinked", "exact polygon gauge (kinked)", make_kinked,
                                     view, center, radius, stripes, (kp, knrm, kcurves))
            info.update(kinked_normal_jump_deg=float(f"{kjump:.3g}"))
            # second row: close-ups of the vertex that faces the camera most directly
            d = np.asarray(view, dtype=np.float64) / np.linalg.norm(view)
            k = int(np.argmax(nrm[:len(v)] @ d))
            near = 0.35 * np.median(np.linalg.norm(v[meshes.edge_array(f)[:, 0]]
                                                   - v[meshes.edge_array(f)[:, 1]], axis=1))
            zoom = [self._zebra_half(f"{tag}_zoom", f"{caption}, close-up", make, view, pts[k], near,
                                     stripes, overlay_)
                    for tag, caption, make, overlay_ in (
                        ("gerbs", "GERBS", lambda m: m.surface_object("GERBS", pts, tris, cn),
                         (pts, nrm, curves)),
                        ("kinked", "exact gauge (kinked)", make_kinked, (kp, knrm, kcurves)))]
            top, bottom = sc.side_by_side([left, right]), sc.side_by_side(zoom)
            gap = np.ones((4,) + top.shape[1:], dtype=top.dtype)
            return sc.save_png(np.concatenate([top, gap, bottom]), self.out / f"{name}.png"), info
        return sc.save_png(sc.side_by_side([left, right]), self.out / f"{name}.png"), info

    def crease_pair(self, name: str):
        """Zebra of a smooth mesh with one fully creased edge loop | without creases; the
        normal jump across the crease and elsewhere are measured on the way."""
        from figures import scene as sc

        spec = CREASE_SCENE
        v, f, creases = spec["mesh"]()
        res = spec["resolution"][1 if self.quick else 0]
        halves, info = [], {"resolution": res}
        for tag, caption, opts in (("creased", "GERBS, one edge loop creased", {"creases": creases}),
                                   ("smooth", "GERBS, no creases", {})):
            pts, tris, cn, nrm, jump, _ = gerbs.tessellate_split(v, f, res, **opts)
            if not halves:
                center, radius = sc.bounding_sphere(pts)
            info[f"{tag}_normal_jump_deg"] = float(f"{jump:.3g}")
            halves.append(self._zebra_half(
                tag, caption, lambda m, p=pts, t=tris, c=cn: m.surface_object("GERBS", p, t, c),
                spec["view"], center, radius, spec["stripes"]))
        return sc.save_png(sc.side_by_side(halves), self.out / f"{name}.png"), info

    def zebra_peers(self, name: str):
        """GERBS | Modified Butterfly | Catmull-Clark panels with one camera, lights and
        stripe material, framed on the GERBS surface; captions carry the output counts."""
        from figures import peers
        from figures import scene as sc

        spec = PEER_SCENES[name]
        v, f = spec["mesh"]()
        level = PEER_LEVEL[1 if self.quick else 0]
        panels = peers.zebra_surfaces(v, f, level)
        center, radius = sc.bounding_sphere(np.concatenate([p[1] for p in panels]))
        radius *= spec["zoom"]  # the box's sphere is loose around the silhouette
        images, info = [], {"level": level}
        for k, (caption, pts, tris, nrm) in enumerate(panels):
            make = lambda m, pts=pts, tris=tris, nrm=nrm: m.surface_object("Surface", pts, tris, nrm)  # noqa: E731
            images.append(self._zebra_half(f"{name}_{k}", caption, make, spec["view"], center,
                                           radius, spec["stripes"]))
            info[caption.split(",")[0]] = len(pts)
        return sc.save_png(sc.side_by_side(images), self.out / f"{name}.png"), info

    def render(self, name: str):
        if name in WIRE_SCENES:
            return self.wire_figure(name)
        if name == "zebra_crease":
            return self.crease_pair(name)
        if name in PEER_SCENES:
            return self.zebra_peers(name)
        return self.zebra_pair(name)

    def close(self):
        shutil.rmtree(self.tmp, ignore_errors=True)


def _unit(n):
    n = np.asarray(n, dtype=np.float64)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def _faces_camera(v, face, eye) -> bool:
    """Whether the (Newell) normal of a polygon points towards the eye."""
    p = v[list(face)]
    n = np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
    return float(np.dot(n, eye - p.mean(axis=0))) > 0.0


# ---------------------------------------------------------------- main


def _size(text: str):
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--size must look like 800x600, got {text!r}") from None
    if w < 8 or h < 8:
        raise argparse.ArgumentTypeError("--size must be at least 8x8")
    return w, h


def _samples(text: str) -> int:
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"--samples must be >= 1, got {n}")
    return n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img")
    ap.add_argument("--size", type=_size, default=(800, 600), help="WxH of one render; zebra renders are HxH squares (default 800x600)")
    ap.add_argument("--samples", type=_samples, default=24, help="Cycles samples per pixel (default 24)")
    ap.add_argument("--only", nargs="+", choices=ALL_FIGURES, metavar="NAME",
                    help="render only these figures: " + ", ".join(ALL_FIGURES))
    ap.add_argument("--quick", action="store_true", help="coarse tessellations and data (for tests)")
    args = ap.parse_args(argv)
    names = args.only or list(ALL_FIGURES)
    args.out.mkdir(parents=True, exist_ok=True)
    w, h = args.size
    total = time.perf_counter()
    renderer = None
    try:
        for name in names:
            t0 = time.perf_counter()
            if name in BLENDER_FIGURES:
                if renderer is None:
                    renderer = Renderer(args.out, w, h, args.samples, args.quick)
                path, info = renderer.render(name)
            else:
                from figures import plots

                path, info = plots.FIGURES[name](args.out, (w, h), quick=args.quick)
            print(f"{name:14s} {time.perf_counter() - t0:7.1f} s  {path}  {info}", flush=True)
    finally:
        if renderer is not None:
            renderer.close()
    print(f"total          {time.perf_counter() - total:7.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
