"""Meshes nobody made for this project build (issue 14): pymeshlab's sample meshes
(scans with unreferenced vertices, a textured bunny with boundaries) in the core and
through the CLI, and meshes written by Blender's own exporters (glTF with split normals
and UV seams, PLY with UVs, STL without connectivity) read back by its importers."""
from pathlib import Path

import bpy
import numpy as np
import pytest

import pymeshlab

from .helpers import positions, topology

pytestmark = pytest.mark.blender

SAMPLES = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
ROOT = Path(__file__).resolve().parents[2]
# name: (vertices, faces, the repair's warnings as {tag: count})
EXPECTED = {
    "cow.obj": (2904, 5804, {}),
    "airplane.obj": (7017, 10796, {"unused_vertex": 1617}),
    "bone.ply": (1872, 3022, {"unused_vertex": 359}),
    "bunny10k_textured.obj": (5051, 9999, {}),
    "bunny.obj": (28088, 56172, {}),
}


def _load(name):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLES / name))
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_pymeshlab_samples_repair_to_valid_manifolds(name):
    from gerbs_core.mesh.repair import repair_mesh

    V, F = _load(name)
    nv, nf, tags = EXPECTED[name]
    assert (len(V), len(F)) == (nv, nf)
    r = repair_mesh(V, F)
    assert {w.tag: len(w.indices) for w in r.warnings} == tags
    unused = np.setdiff1d(np.arange(len(V)), F)
    assert np.array_equal(r.vertex_map, np.setdiff1d(np.arange(len(V)), unused))
    assert r.topology.n_faces == len(F)


def test_bone_scan_builds_an_interpolating_surface():
    """bone.ply: 359 of its 1872 vertices are in no face; the whole surface is built."""
    from gerbs_core.mesh import BlendingSurface

    V, F = _load("bone.ply")
    s = BlendingSurface(V, F)
    assert [(w.tag, len(w.indices)) for w in s.warnings] == [("unused_vertex", 359)]
    T = s.topology
    S = s.evaluate(T.corner_face, s.layouts.corners)
    assert np.abs(S - V[s.vertex_map[T.face_vertices]]).max() <= 1e-12
    assert np.all(np.isfinite(s.tessellate(2)[0]))


def test_cli_builds_a_scan_with_unreferenced_vertices(tmp_path):
    import subprocess
    import sys

    out = subprocess.run([sys.executable, str(ROOT / "scripts" / "gerbs_surface.py"),
                          str(SAMPLES / "bone.ply"), "-o", str(tmp_path / "bone.obj"),
                          "--resolution", "2", "--quiet"], capture_output=True, text=True,
                         cwd=tmp_path, env={"OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin"})
    assert out.returncode == 0, out.stderr
    lines = [x for x in out.stderr.splitlines() if x.startswith("warning:")]
    assert len(lines) == 1 and "unused_vertex" in lines[0], out.stderr
    assert (tmp_path / "bone.obj").stat().st_size > 0


def _suzanne_export(tmp_path, ext):
    """Suzanne, flat shaded and with UVs (so the glTF/PLY exporters split vertices),
    exported by Blender and read back by Blender's importer."""
    bpy.ops.wm.obj_import(filepath=str(ROOT / "examples" / "suzanne.obj"))
    obj = bpy.context.selected_objects[0]
    if not obj.data.uv_layers:
        bpy.context.view_layer.objects.active = obj
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        bpy.ops.uv.smart_project()
        bpy.ops.object.mode_set(mode="OBJECT")
    obj.data.shade_flat()
    path = tmp_path / f"suzanne{ext}"
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    if ext == ".glb":
        bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", use_selection=True)
    elif ext == ".ply":
        bpy.ops.wm.ply_export(filepath=str(path), export_selected_objects=True, export_uv=True)
    else:
        bpy.ops.wm.stl_export(filepath=str(path), export_selected_objects=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if ext == ".glb":
        bpy.ops.import_scene.gltf(filepath=str(path), merge_vertices=False)
    elif ext == ".ply":
        bpy.ops.wm.ply_import(filepath=str(path))
    else:
        bpy.ops.wm.stl_import(filepath=str(path))
    (imported,) = [o for o in bpy.data.objects if o.type == "MESH"]
    return imported


@pytest.mark.parametrize("ext", [".glb", ".ply", ".stl"])
def test_blender_exports_build_with_seams_named_and_welded_on_request(blender, tmp_path, ext):
    from gerbs_core.datasets.primitives import suzanne
    from gerbs_core.mesh import BlendingSurface
    from blender_addon.mesh_io import faces_from_csr

    obj = _suzanne_export(tmp_path, ext)
    X = positions(obj.data).astype(np.float64)
    offsets, corners = topology(obj.data)
    faces = faces_from_csr(offsets, corners)
    s = BlendingSurface(X, faces)
    tags = {w.tag: w for w in s.warnings}
    X0, F0 = suzanne()
    if ext == ".stl":  # joined by position: the 2 vertex pairs Suzanne shares become bow-ties
        # (Blender's triangulation of her quads folds the surface at the mouth's corners:
        # it crosses itself there, and says so)
        assert [t for t in tags if t != "self_crossing"] == ["non_manifold_vertex"]
        assert len(tags["non_manifold_vertex"].indices) == 2
        assert s.topology.n_vertices == len(X0)
    else:  # split at every flat-shaded edge / UV seam: an open seam, named (PLY: seams
        # meeting at a vertex leave fans touching there, split as bow-ties)
        assert len(X) > len(X0) and "open_seam" in tags
        assert set(tags) <= {"open_seam", "non_manifold_vertex"}
        assert len(tags["open_seam"].indices) > 100 and tags["open_seam"].edges
    T = s.topology
    S = s.evaluate(T.corner_face, s.layouts.corners)
    assert np.abs(S - X[s.vertex_map[T.face_vertices]]).max() <= 1e-12
    welded = BlendingSurface(X, faces, merge_distance=0.0)
    assert "open_seam" not in {w.tag for w in welded.warnings}
    from gerbs_core.mesh import MeshTopology
    holes = int(MeshTopology(F0, len(X0)).edge_is_boundary.sum())  # Suzanne's eyes
    W = welded.topology  # (the glTF exporter triangulates)
    assert W.n_vertices == len(X0) and W.n_faces == len(faces)
    assert int(W.edge_is_boundary.sum()) == holes  # no seam left open
    assert np.all(np.isfinite(welded.tessellate(2)[0]))
