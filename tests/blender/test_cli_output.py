"""What the command-line job hands a new user (found by a newcomer's walk through the
README, 2026-12-06): a smooth-shaded result from a flat-shaded input, one error line
from the wrong Python, messages in the command line's words, no temporary paths."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.blender

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "gerbs_surface.py"
SAMPLE = ROOT / "examples" / "suzanne.obj"   # exported flat shaded: "s 0", no normals
ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


def run(*args, cwd, python=(sys.executable,)):
    return subprocess.run([*python, str(SCRIPT), *map(str, args)], cwd=cwd, env=ENV,
                          capture_output=True, text=True, timeout=300)


def shading(path):
    """(the OBJ's smoothing-group lines, its vertex and normal counts): Blender's OBJ
    exporter writes "s 1" and one normal per vertex for smooth faces, "s 0" and one normal
    per face for flat ones."""
    lines = path.read_text().splitlines()
    groups = {x for x in lines if x.startswith("s ")}
    return groups, sum(x.startswith("v ") for x in lines), sum(x.startswith("vn ") for x in lines)


def test_a_flat_shaded_input_gives_a_smooth_shaded_surface_unless_kept(tmp_path):
    assert "s 0" in SAMPLE.read_text().splitlines()           # the sample is flat shaded
    out = run(SAMPLE, "-o", tmp_path / "s.obj", "--resolution", "2", "--quiet", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    groups, nv, nn = shading(tmp_path / "s.obj")
    assert groups == {"s 1"} and nn <= nv                       # normals shared at vertices
    # --shading keep: the input faces' shading, as the modifier carries it in Blender
    out = run(SAMPLE, "-o", tmp_path / "k.obj", "--resolution", "2", "--quiet",
              "--shading", "keep", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    groups, nv, nn = shading(tmp_path / "k.obj")
    assert groups == {"s 0"} and nn > nv                        # one normal per face
    assert SAMPLE.read_text().count("s 0") == 1                # the input is not written


def test_a_flat_export_with_normals_gives_smooth_normals_unless_creased(blender, tmp_path):
    """Blender's Monkey written flat with its normals (a newcomer's walk, 2026-12-07): the
    OBJ importer marks the edges between faces of different normals sharp (961 of 1,005),
    and the modifier carried them onto the output, splitting its normals along every cage
    edge (12,170 normals for 7,830 points). --shading smooth clears them; a full crease
    stays sharp, where the surface has its crease."""
    import bpy
    bpy.ops.mesh.primitive_monkey_add()
    src = tmp_path / "monkey.obj"
    bpy.ops.wm.obj_export(filepath=str(src), export_normals=True, export_smooth_groups=False,
                          export_materials=False)
    text = src.read_text().splitlines()
    assert sum(x.startswith("vn ") for x in text) > 400            # one normal per face
    out = run(src, "-o", tmp_path / "s.obj", "--resolution", "2", "--quiet", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    groups, nv, nn = shading(tmp_path / "s.obj")
    assert groups == {"s 1"} and nn == nv, (nn, nv)                 # one normal per point
    # a fully creased edge keeps its normals split (the cube's 12 edges at 60 degrees)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    cube = tmp_path / "cube.obj"
    bpy.ops.wm.obj_export(filepath=str(cube), export_normals=True, export_materials=False)
    out = run(cube, "-o", tmp_path / "c.obj", "--resolution", "2", "--quiet",
              "--crease-angle", "60", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    groups, nv, nn = shading(tmp_path / "c.obj")
    # 26 points (8 corners, 12 edge midpoints, 6 face centres), every face flat: with its
    # normals split at the creases the exporter writes the faces' 6 distinct normals (26,
    # one per point, if the creases were shaded smooth)
    assert nv == 26 and nn == 6, (nv, nn)


def test_an_obj_output_keeps_the_materials_in_its_own_mtl(blender, tmp_path):
    """A newcomer's walk (2026-12-07): the .obj output dropped the materials a .glb keeps
    (the exporter ran with export_materials=False). Now a .mtl beside it carries them, only
    where the input has materials, and never replaces a library the input names."""
    import bpy
    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.object
    for name in ("Grey", "Red"):
        cube.data.materials.append(bpy.data.materials.new(name))
    cube.data.polygons[2].material_index = 1
    src = tmp_path / "mat.obj"
    bpy.ops.wm.obj_export(filepath=str(src))
    out = run(src, "-o", tmp_path / "m.obj", "--resolution", "2", "--quiet", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    text = (tmp_path / "m.obj").read_text().splitlines()
    assert "mtllib m.mtl" in text and {"usemtl Grey", "usemtl Red"} <= set(text)
    assert "newmtl Red" in (tmp_path / "m.mtl").read_text()
    # the Red face's 4 output quads at r = 2, the Grey faces' 20
    faces = {}
    current = None
    for line in text:
        if line.startswith("usemtl "):
            current = line.split()[1]
        elif line.startswith("f "):
            faces[current] = faces.get(current, 0) + 1
    assert faces == {"Grey": 20, "Red": 4}, faces
    # an output whose .mtl would replace the input's library is refused before writing
    (tmp_path / "lib").mkdir()
    src2 = tmp_path / "lib" / "part.obj"
    src2.write_text(src.read_text().replace("mtllib mat.mtl", "mtllib shared.mtl"))
    (tmp_path / "lib" / "shared.mtl").write_text((tmp_path / "mat.mtl").read_text())
    before = (tmp_path / "lib" / "shared.mtl").read_text()
    out = run(src2, "-o", tmp_path / "lib" / "shared.obj", "--resolution", "2", "--quiet",
              cwd=tmp_path)
    assert out.returncode == 2 and "would replace shared.mtl" in out.stderr, out.stderr
    assert "warning" not in out.stderr      # said before the build, not after its lines
    assert (tmp_path / "lib" / "shared.mtl").read_text() == before
    assert not (tmp_path / "lib" / "shared.obj").exists()
    # no materials: no .mtl
    out = run(SAMPLE, "-o", tmp_path / "s.obj", "--resolution", "2", "--quiet", cwd=tmp_path)
    assert out.returncode == 0 and not (tmp_path / "s.mtl").exists()


def test_a_rigged_gltf_gives_a_valid_still_surface_and_says_what_it_leaves_out(blender,
                                                                             tmp_path):
    """An export test (2026-12-07): a glTF with a skinned, animated limb and a cube with a
    morph target came out with the rig and morphs dropped silently, a 'weights' animation
    channel aimed at a mesh without morph targets (an invalid glTF), and a surface built
    for the bone shape the importer adds (hidden, not exported)."""
    import json
    import struct

    import bpy
    bpy.ops.mesh.primitive_cylinder_add(vertices=8, depth=4, location=(0, 0, 2))
    limb = bpy.context.object
    limb.name = "Limb"
    bpy.ops.object.armature_add(location=(0, 0, 0))
    arm = bpy.context.object
    limb.parent = arm
    group = limb.vertex_groups.new(name=arm.data.bones[0].name)
    group.add(list(range(len(limb.data.vertices))), 1.0, "REPLACE")
    limb.modifiers.new("Armature", "ARMATURE").object = arm
    arm.pose.bones[0].keyframe_insert("rotation_quaternion", frame=1)
    bpy.ops.mesh.primitive_cube_add(location=(4, 0, 0))
    cube = bpy.context.object
    cube.name = "Morph"
    cube.shape_key_add(name="Basis")
    key = cube.shape_key_add(name="Up")
    key.data[0].co.z += 1.0
    key.keyframe_insert("value", frame=1)
    src = tmp_path / "rig.glb"
    bpy.ops.export_scene.gltf(filepath=str(src), export_skins=True, export_morph=True,
                              export_animations=True)
    out = run(src, "-o", tmp_path / "o.glb", "--resolution", "2", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "Limb: its skin (armature) and animation are not written" in out.stderr
    assert "Morph: its shape keys (morph targets) and animation are not written" in out.stderr
    built = [x.split(":")[0] for x in out.stderr.splitlines() if "surface with" in x]
    assert sorted(built) == ["Limb", "Morph"], built                  # no bone shape
    data = (tmp_path / "o.glb").read_bytes()
    doc = json.loads(data[20:20 + struct.unpack("<I", data[12:16])[0]])
    assert not doc.get("animations") and not doc.get("skins")
    assert sorted(n.get("name") for n in doc["nodes"]) == ["Limb", "Morph"]


def test_a_z_up_obj_stands_upright_in_gltf_with_up_axis_z(blender, tmp_path):
    """An export test (2026-12-07): an OBJ written Z-up (CAD, 3D printing) came out of the
    CLI on its side in glTF, with no option to say so. --up-axis Z reads it Z-up: the glTF,
    read back into Blender, stands upright, and an OBJ output keeps z as its up axis."""
    import bpy
    import numpy as np

    corners = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (0.0, 4.0)]
    faces = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3),
             (2, 4, 8, 6)]                                   # a 1 x 1 x 4 tower, z up
    src = tmp_path / "tower.obj"
    src.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners)
                   + "".join("f " + " ".join(map(str, f)) + "\n" for f in faces))

    def tall_axis_in_blender(path):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.import_scene.gltf(filepath=str(path))
        (obj,) = [o for o in bpy.data.objects if o.type == "MESH"]
        V = np.array([v.co[:] for v in obj.data.vertices])
        W = V @ np.array(obj.matrix_world)[:3, :3].T
        return int(np.argmax(np.ptp(W, axis=0)))

    for up, tall in ((None, 1), ("Z", 2)):       # Blender's z is up; on its side: its y
        args = ["--up-axis", up] if up else []
        out = run(src, "-o", tmp_path / f"t{up}.glb", "--resolution", "2", "--quiet", *args,
                  cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        assert tall_axis_in_blender(tmp_path / f"t{up}.glb") == tall, up
    out = run(src, "-o", tmp_path / "t.obj", "--resolution", "2", "--quiet", "--up-axis", "Z",
              cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    V = np.array([[float(c) for c in line.split()[1:4]]
                  for line in (tmp_path / "t.obj").read_text().splitlines()
                  if line.startswith("v ")])
    assert np.argmax(np.ptp(V, axis=0)) == 2                 # still z up
    out = run(tmp_path / "tNone.glb", "-o", tmp_path / "x.glb", "--up-axis", "Z", cwd=tmp_path)
    assert out.returncode == 2 and "--up-axis: a glTF input is Y-up" in out.stderr


def test_the_wrong_python_gets_one_error_line_naming_the_environment(tmp_path):
    # -S: no site-packages, so no bpy (as a system Python without the project's environment)
    out = run(cwd=tmp_path, python=(sys.executable, "-S"))
    assert out.returncode == 2
    assert "Traceback" not in out.stderr, out.stderr
    (line,) = [x for x in out.stderr.splitlines() if x.startswith("error:")]
    assert "'bpy'" in line and str(ROOT / ".venv" / "bin" / "python") in line
    assert not (tmp_path / "out").exists()


def test_a_bpy_that_does_not_load_says_so(tmp_path):
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "bpy.py").write_text("import a_library_bpy_needs_xyz\n")  # bpy there, its need not
    env = {**ENV, "PYTHONPATH": str(fake)}
    out = subprocess.run([sys.executable, "-S", str(SCRIPT)], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    (line,) = [x for x in out.stderr.splitlines() if x.startswith("error:")]
    assert "'bpy' module does not load" in line and "a_library_bpy_needs_xyz" in line


def test_messages_name_the_command_line_options_and_no_temporary_path(tmp_path):
    out = run(SAMPLE, "-o", tmp_path / "m.obj", "--memory-budget", "1", "--resolution", "40",
              "--quiet", cwd=tmp_path)
    assert out.returncode == 2
    assert "(--memory-budget)" in out.stderr and "memory_budget" not in out.stderr, out.stderr
    seam = tmp_path / "seam.obj"     # two triangles touching along an unwelded edge
    seam.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 5 4\n")
    out = run(seam, "-o", tmp_path / "seam_out.obj", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    (warn,) = [x for x in out.stderr.splitlines() if "open_seam" in x]
    assert "--merge-distance welds them" in warn
    # the export's own "Writing to <temporary folder>" is not shown; our line says where
    assert ".gerbs-" not in out.stdout + out.stderr
    assert f"writing {tmp_path / 'seam_out.obj'} ..." in out.stderr


def test_replacing_an_earlier_output_is_said(tmp_path):
    """cube.obj and cube.stl both default to out/cube_gerbs.glb: the second run says so."""
    first = run(SAMPLE, "--resolution", "1", "--quiet", cwd=tmp_path)
    assert first.returncode == 0 and "replaces" not in first.stderr, first.stderr
    again = run(SAMPLE, "--resolution", "1", "--quiet", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    out = tmp_path / "out" / "suzanne_gerbs.glb"
    assert f"wrote {out} (replacing the file that was there)" in again.stderr
