"""The command-line job with creases: --crease-angle and --sharp-creases (real bpy
subprocesses, the style of test_scripts.py)."""
import bpy
import numpy as np
import pytest

from .helpers import positions
from .test_scripts import ROOT, run

pytestmark = pytest.mark.blender

SCRIPT = ROOT / "scripts" / "gerbs_surface.py"


def _cube_obj(path):
    from gerbs_core.datasets.primitives import cube
    V, F = cube()
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in V]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in F]
    path.write_text("\n".join(lines) + "\n")
    return path


def _cube_distance(S, h=1.0):
    inside = np.minimum(np.abs(S + h), np.abs(S - h)).min(axis=1)
    outside = np.linalg.norm(np.maximum(np.abs(S) - h, 0.0), axis=1)
    return np.where(outside > 0, outside, inside)


def _result(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.obj_import(filepath=str(path))
    (obj,) = bpy.context.selected_objects
    return positions(obj.data)


def test_crease_angle_keeps_the_cube_a_cube(blender, tmp_path):
    src = _cube_obj(tmp_path / "cube.obj")
    out = run([SCRIPT, src, "-o", tmp_path / "c.obj", "--resolution", "4",
               "--crease-angle", "60"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "12 edges creased" in out.stderr
    P = _result(tmp_path / "c.obj")
    print(f"--crease-angle 60: {len(P)} points, max distance to the cube "
          f"{_cube_distance(P).max():.1e}")
    assert len(P) > 8 and _cube_distance(P).max() <= 1e-5
    # above the cube's 90 degrees nothing is creased: the cube is rounded
    out = run([SCRIPT, src, "-o", tmp_path / "r.obj", "--resolution", "4", "--quiet",
               "--crease-angle", "120"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert _cube_distance(_result(tmp_path / "r.obj")).max() > 0.05


def test_sharp_creases_from_the_importers_sharp_edges(blender, tmp_path):
    """Blender's OBJ importer marks edges sharp between faces of different smoothing groups
    or with split normals; a cube written by Blender (flat faces) comes back all sharp."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    bpy.ops.wm.obj_export(filepath=str(tmp_path / "b.obj"), export_materials=False)
    out = run([SCRIPT, tmp_path / "b.obj", "-o", tmp_path / "s.obj", "--resolution", "3",
               "--sharp-creases"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "12 edges creased" in out.stderr
    assert _cube_distance(_result(tmp_path / "s.obj")).max() <= 1e-5
    # the summary counts the faces as written (a newcomer's walk: it named the triangles
    # only, 15,488 for Suzanne's 8,000 output faces)
    faces = sum(x.startswith("f ") for x in (tmp_path / "s.obj").read_text().splitlines())
    assert faces == 54 and "56 points, 54 faces (108 triangles)" in out.stderr, out.stderr


@pytest.mark.parametrize("value", ["-5", "200", "nan"])
def test_bad_crease_angle_is_one_error_line(tmp_path, value):
    src = _cube_obj(tmp_path / "cube.obj")
    out = run([SCRIPT, src, "-o", tmp_path / "x.obj", "--crease-angle", value], cwd=tmp_path)
    assert out.returncode == 2
    assert out.stderr.strip().splitlines()[-1].startswith("error: --crease-angle")
    assert not (tmp_path / "x.obj").exists()


def test_gltf_creases_are_measured_after_the_weld(blender, tmp_path):
    """A glTF arrives split at every seam (Blender's Cube as six separate quads, each two
    triangles): without --merge-distance no edge joins two faces of different sides, so
    nothing is creased and the line says why; with it the copy is welded first and the
    cube's 12 edges are creased, by angle and by the file's split normals alike. A
    smooth-by-angle Cylinder's split normals crease its 64 rim edges and none of the 32
    side edges, whose normals are shared (the control)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    bpy.ops.export_scene.gltf(filepath=str(tmp_path / "cube.glb"), use_selection=True)
    bpy.ops.object.delete()
    bpy.ops.mesh.primitive_cylinder_add()
    bpy.ops.object.shade_smooth_by_angle(angle=0.6)
    bpy.ops.export_scene.gltf(filepath=str(tmp_path / "cyl.glb"), use_selection=True)
    src = tmp_path / "cube.glb"
    out = run([SCRIPT, src, "-o", tmp_path / "a.obj", "--resolution", "3", "--quiet",
               "--crease-angle", "30"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "0 edges creased (vertices share positions" in out.stderr
    assert "--merge-distance 0 welds them" in out.stderr
    for option in (["--crease-angle", "30"], ["--sharp-creases"]):
        out = run([SCRIPT, src, "-o", tmp_path / "c.obj", "--resolution", "3",
                   "--merge-distance", "0", *option], cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        assert "Cube: 12 edges creased" in out.stderr, option
        assert _cube_distance(_result(tmp_path / "c.obj")).max() <= 1e-5
    out = run([SCRIPT, tmp_path / "cyl.glb", "-o", tmp_path / "y.obj", "--resolution", "2",
               "--merge-distance", "0", "--sharp-creases"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "Cylinder: 64 edges creased" in out.stderr


def test_split_normals_follow_their_corners_through_a_weld_that_removes_a_face(blender, tmp_path):
    """A review's find: the weld drops faces it makes degenerate (here a sliver triangle
    whose corner lies 2e-5 from a cube corner), and the file's corner normals, taken
    before it, then belonged to other corners: 16 edges creased on a cube. They now ride
    along the weld as a corner attribute: the cube's 12."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    V = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1), (-1, -1, 1), (1, -1, 1), (1, 1, 1),
         (-1, 1, 1), (-1 + 2e-5, -1, 1)]
    F = [(0, 3, 2, 1), (0, 1, 5, 8, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7), (4, 8, 6),
         (8, 5, 6), (4, 6, 7)]
    mesh = bpy.data.meshes.new("sliver")
    mesh.from_pydata(V, [], F)
    mesh.update()
    obj = bpy.data.objects.new("sliver", mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.select_set(True)
    bpy.ops.export_scene.gltf(filepath=str(tmp_path / "sliver.glb"), use_selection=True)
    out = run([SCRIPT, tmp_path / "sliver.glb", "-o", tmp_path / "s.obj", "--resolution", "2",
               "--merge-distance", "1e-3", "--sharp-creases"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "sliver: 12 edges creased" in out.stderr
