"""The extension zips from scripts/build_extension.py: one per platform, valid for
Blender, carrying unmodified scipy wheels for Python 3.11 and 3.13 and the core as
the add-on's own code; the Linux zip installed into a bare bpy 5.0.1 works.

The zips are built offline from the wheel cache that ``scripts/install.sh`` fills
(``build_extension.py fetch``); a missing cache fails with how to fill it.
"""
from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import re
import subprocess
import sys
import tomllib
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
INSTALL = Path(__file__).parent / "subprocess" / "install_extension.py"
sys.path.insert(0, str(ROOT / "scripts"))
import build_extension as bx  # noqa: E402

pytestmark = pytest.mark.blender


@pytest.fixture(scope="module")
def zips(tmp_path_factory) -> dict:
    """{Blender platform: zip path}, all four built from the cache."""
    try:
        paths = bx.build(bx.CACHE, tmp_path_factory.mktemp("dist"))
    except SystemExit as exc:
        pytest.fail(f"building the extension zips failed: {exc}", pytrace=False)
    return {p: z for p, z in zip(bx.PLATFORMS, paths)}


def manifest(zip_path: Path) -> dict:
    """The zip's manifest as Blender reads it: Blender's ``--split-platforms`` build
    keeps the source lists and writes the zip's own in ``[build.generated]``."""
    with zipfile.ZipFile(zip_path) as zf:
        data = tomllib.loads(zf.read("blender_manifest.toml").decode())
    return {**data, **data.get("build", {}).get("generated", {})}


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def test_one_zip_per_platform_passes_blenders_validation(zips, tmp_path):
    assert set(zips) == {"windows-x64", "macos-arm64", "macos-x64", "linux-x64"}
    for platform, path in zips.items():
        assert path.name.endswith(f"-{platform.replace('-', '_')}.zip")
        assert bx.validate(path).startswith("Success"), path
        data = manifest(path)
        assert data["platforms"] == [platform]
        assert data["blender_version_min"] == "4.2.0" and "blender_version_max" not in data
        assert path.stat().st_size < bx.MAX_ZIP_MB * 2 ** 20
    # the validator is not a rubber stamp: a two-number blender_version_min is refused
    broken = tmp_path / "broken.zip"
    with zipfile.ZipFile(zips["linux-x64"]) as src, zipfile.ZipFile(broken, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "blender_manifest.toml":
                data = data.replace(b'blender_version_min = "4.2.0"', b'blender_version_min = "4.2"')
            dst.writestr(item, data)
    with pytest.raises(SystemExit, match="blender_version_min"):
        bx.validate(broken)


def test_each_zip_carries_its_platforms_wheels_unmodified_for_both_pythons(zips):
    for platform, path in zips.items():
        with zipfile.ZipFile(path) as zf:
            names = zf.namelist()
            wheels = [n for n in names if n.startswith("wheels/")]
            listed = [w.removeprefix("./") for w in manifest(path)["wheels"]]
            assert sorted(listed) == sorted(wheels)
            tags = [bx.wheel_tags(w) for w in wheels]
            assert sorted(t["python"] for t in tags) == ["cp311", "cp313"], wheels
            assert {t["name"] for t in tags} == {"scipy"}, wheels  # no numpy, no core wheel
            for wheel in wheels:
                assert bx.blender_platforms(wheel) == [platform], wheel
                cached = bx.CACHE / Path(wheel).name
                assert sha256(zf.read(wheel)) == sha256(cached.read_bytes()), wheel
            core = {n.removeprefix("gerbs_core/") for n in names
                    if n.startswith("gerbs_core/") and n.endswith(".py")}
            repo = {p.relative_to(ROOT / "gerbs_core").as_posix()
                    for p in (ROOT / "gerbs_core").rglob("*.py")}
            assert core == repo
            assert zf.read("gerbs_core/errors.py") == (ROOT / "gerbs_core/errors.py").read_bytes()
            assert "core.py" in names and "__init__.py" in names


def test_the_wheel_check_sees_a_wrong_platform():
    assert bx.blender_platforms("scipy-1.17.1-cp311-cp311-win_amd64.whl") == ["windows-x64"]
    assert bx.blender_platforms(
        "scipy-1.17.1-cp313-cp313-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl") == ["linux-x64"]
    assert bx.blender_platforms("scipy-1.17.1-cp311-cp311-macosx_12_0_arm64.whl") != ["macos-x64"]


def test_numpy_is_not_shipped_only_while_blenders_own_satisfies_scipy(tmp_path):
    """The build refuses a scipy that needs a newer numpy than Blender 4.2 bundles."""
    for requirement, refused in (("numpy<2.7,>=1.26.4", False), ("numpy>=2.0", True)):
        wheel = tmp_path / f"scipy-9-cp311-cp311-win_amd64-{refused}.whl"
        with zipfile.ZipFile(wheel, "w") as zf:
            zf.writestr("scipy-9.dist-info/METADATA", f"Name: scipy\nRequires-Dist: {requirement}\n")
        if refused:
            with pytest.raises(SystemExit, match="numpy"):
                bx._check_numpy(wheel)
        else:
            bx._check_numpy(wheel)


def test_addon_imports_the_core_only_through_its_shim():
    """A direct ``import gerbs_core`` would work in a checkout and fail in the zip."""
    direct = [f"{p.name}:{i + 1}" for p in sorted((ROOT / "blender_addon").glob("*.py"))
              for i, line in enumerate(p.read_text().splitlines())
              if re.match(r"\s*(from|import)\s+gerbs_core\b", line)]
    assert direct == []


def bare_python(directory: Path) -> Path:
    """A venv holding only bpy and numpy (symlinked from this one): no scipy, no gerbs_core."""
    venv.create(directory, with_pip=False, symlinks=True)
    site = next(directory.glob("lib/python*/site-packages"))
    source = Path(importlib.util.find_spec("bpy").origin).parents[1]
    for name in ("bpy", "numpy", "numpy.libs"):
        if (source / name).exists():
            (site / name).symlink_to(source / name)
    return directory / "bin" / "python"


def install(python: Path, zip_path: Path, tmp: Path, *flags) -> dict:
    user = tmp / "user"
    user.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env.update(BLENDER_USER_RESOURCES=str(user), OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([str(python), str(INSTALL), str(zip_path), *flags], cwd=tmp, env=env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-4000:]
    assert "Traceback" not in out.stderr, out.stderr[-4000:]
    line = next(x for x in out.stdout.splitlines() if x.startswith("RESULT "))
    return json.loads(line[7:])


def test_linux_zip_installs_into_a_bare_bpy_and_builds_the_surface(zips, tmp_path):
    result = install(bare_python(tmp_path / "venv"), zips["linux-x64"], tmp_path)
    assert result["error"] == "" and result["op_error"] == "", result
    assert result["points"] == 1980, result  # Suzanne (507 vertices) at resolution 2
    assert str(tmp_path / "user") in result["scipy_from"], result  # the zip's own cp311 wheel
    assert result["removed"], result


def without_wheels(zip_path: Path, out: Path) -> Path:
    """The zip as it would be without its scipy wheels (manifest and files)."""
    with zipfile.ZipFile(zip_path) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            if item.filename == "blender_manifest.toml":
                text = re.sub(r"\nwheels = \[[^\]]*\]\n", "\n", src.read(item).decode())
                assert "\nwheels" not in text
                dst.writestr(item, text)
            elif not item.filename.startswith("wheels/"):
                dst.writestr(item, src.read(item))
    return out


def test_zip_without_scipy_installs_and_says_so_on_first_use(zips, tmp_path):
    bare = without_wheels(zips["linux-x64"], tmp_path / "no_scipy.zip")
    result = install(bare_python(tmp_path / "venv"), bare, tmp_path)
    assert result["scipy_from"] == "", result
    assert result["error"].startswith("GERBS: scipy is not available to this Blender"), result
    assert "zip built for this platform" in result["error"], result
    assert result["error"] in result["status_bar"], result
    assert "scipy is not available" in result["op_error"], result
    assert result["points"] == 507, result  # the base mesh passes through, untouched
    assert result["removed"], result
