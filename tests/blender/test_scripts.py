"""The command-line job, the progress hook and the extension zip (real bpy subprocesses)."""
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import bpy
import numpy as np
import pytest

from .helpers import make_object, positions

pytestmark = pytest.mark.blender

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


def run(args, cwd, env=ENV):
    return subprocess.run([sys.executable, *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def test_progress_callback_reports_monotone_stages(blender):
    from blender_addon import api

    calls = []
    obj = make_object("icosphere")
    api.add_surface(obj, resolution=2, progress=lambda f, msg: calls.append((f, msg)))
    fractions = [f for f, _ in calls]
    assert len(calls) >= 3 and fractions == sorted(fractions) and fractions[-1] == 1.0


def test_main_job_on_the_bundled_sample(tmp_path):
    out = run([ROOT / "scripts" / "gerbs_surface.py"], cwd=tmp_path)  # no arguments at all
    assert out.returncode == 0, out.stderr
    result = tmp_path / "out" / "suzanne_gerbs.glb"
    assert result.is_file() and "100.0%" in out.stderr  # the text progress bar ran
    assert "wrote" in out.stderr


def test_main_job_obj_output_is_the_surface(blender, tmp_path):
    out = run([ROOT / "scripts" / "gerbs_surface.py", ROOT / "examples" / "suzanne.obj",
               "-o", tmp_path / "s.obj", "--resolution", "2", "--boundary", "straighten", "--quiet"],
              cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    bpy.ops.wm.obj_import(filepath=str(tmp_path / "s.obj"))
    (obj,) = bpy.context.selected_objects
    # expected from the core directly (no Blender in the loop)
    from gerbs_core.mesh.surface import BlendingSurface
    from gerbs_core.datasets.primitives import suzanne
    X, F = suzanne()
    P = BlendingSurface(X, F, boundary="straighten").tessellate(2)[0]
    Q = positions(obj.data)
    assert Q.shape == P.shape and np.abs(Q - P).max() <= 1e-5


def test_main_job_invalid_mesh_exits_nonzero_without_output(tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\n")  # edges only: no surface
    out = run([ROOT / "scripts" / "gerbs_surface.py", bad, "-o", tmp_path / "o.glb"], cwd=tmp_path)
    assert out.returncode == 2
    assert "empty" in out.stderr and "error:" in out.stderr
    assert not (tmp_path / "o.glb").exists()


def test_main_job_messy_mesh_prints_warnings_and_exits_zero(tmp_path):
    messy = tmp_path / "messy.obj"
    messy.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\nv -1 0 0\n"
                     "f 1 2 3\nf 2 1 4\nf 1 2 5\n"  # edge 1-2 shared by three faces
                     "f 1 6 7\n")  # ... and a fan meeting the others at vertex 1 only
    out = run([ROOT / "scripts" / "gerbs_surface.py", messy, "-o", tmp_path / "o.obj",
               "--resolution", "2"], cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    lines = [x for x in out.stderr.splitlines() if x.startswith("warning:")]
    assert len(lines) == 2, out.stderr
    assert "non_manifold_edge" in lines[0] and "edges (0, 1)" in lines[0]
    assert "non_manifold_vertex" in lines[1] and "vertex indices [0, 1]" in lines[1]
    assert (tmp_path / "o.obj").is_file()


def test_extension_zip_validates_and_installs(tmp_path):
    wheels = tmp_path / "wheels"
    wheels.mkdir()
    zip_path = tmp_path / "gerbs.zip"
    out = run([ROOT / "scripts" / "build_extension.py", wheels, "-o", zip_path], cwd=tmp_path)
    assert out.returncode == 0, out.stderr + out.stdout
    with zipfile.ZipFile(zip_path) as zf:
        names = set(zf.namelist())
        manifest = zf.read("blender_manifest.toml").decode()
    assert {"__init__.py", "blender_manifest.toml", "api.py", "ids.py"} <= names
    core_wheel = "wheels/gerbs_core-0.1.0-py3-none-any.whl"
    assert core_wheel in names and f'"./{core_wheel}"' in manifest
    # install into a throw-away user directory with Blender's own extension installer
    code = (
        "import bpy, sys\n"
        f"bpy.ops.extensions.package_install_files(filepath={str(zip_path)!r}, "
        "repo='user_default', enable_on_install=True)\n"
        "assert hasattr(bpy.types, 'OBJECT_OT_gerbs_add_surface')\n"
        "mod = sys.modules['bl_ext.user_default.gerbs_blending_surface']\n"
        "bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1)\n"
        "bpy.ops.object.gerbs_add_surface(resolution=2)\n"
        "dg = bpy.context.evaluated_depsgraph_get()\n"
        "print('points', len(bpy.context.object.evaluated_get(dg).data.vertices))\n"
    )
    env = {**ENV, "BLENDER_USER_RESOURCES": str(tmp_path / "user")}
    out = run(["-c", code], cwd=tmp_path, env=env)
    assert out.returncode == 0, out.stderr
    assert "points 42" in out.stdout  # Blender's subdivisions=1: icosahedron, 12 + 30 edges * (2-1)
    site = tmp_path / "user" / "extensions" / ".local" / "lib" / "python3.11" / "site-packages"
    assert (site / "gerbs_core" / "mesh" / "surface.py").is_file()  # the wheel was installed


def test_build_extension_lists_given_wheels_and_skips_numpy(tmp_path):
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        import build_extension
    finally:
        sys.path.pop(0)
    wheels = tmp_path / "wheels"
    extra = build_extension.build_core_wheel(wheels)  # any real wheel file will do
    renamed = extra.rename(wheels / "scipy-1.17.1-py3-none-any.whl")
    (wheels / "numpy-1.26.4-py3-none-any.whl").write_bytes(renamed.read_bytes())
    zip_path = build_extension.build(wheels, tmp_path / "out" / "g.zip")
    with zipfile.ZipFile(zip_path) as zf:
        manifest = zf.read("blender_manifest.toml").decode()
        names = zf.namelist()
    assert '"./wheels/scipy-1.17.1-py3-none-any.whl"' in manifest
    assert "numpy" not in manifest.split("wheels = [")[1]
    assert "wheels/scipy-1.17.1-py3-none-any.whl" in names
    for field in ("schema_version", "id", "version", "name", "tagline", "maintainer", "type",
                  "blender_version_min", "license"):
        assert f"\n{field} = " in manifest
