#!/usr/bin/env python
"""Build the installable Blender extension zip (Blender 4.2+), offline.

    .venv/bin/python scripts/build_extension.py WHEEL_DIR [-o dist/gerbs_blending_surface-0.1.0.zip]

WHEEL_DIR holds the binary wheels Blender's Python lacks, fetched beforehand,
for every platform you want to support, e.g.::

    pip download scipy --only-binary=:all: --python-version 3.11 \
        --platform manylinux_2_28_x86_64 --no-deps -d wheels/
    pip download scipy --only-binary=:all: --python-version 3.11 \
        --platform win_amd64 --no-deps -d wheels/      # and macosx_*_arm64, ...

(``--no-deps``: numpy ships with Blender; numpy wheels found in WHEEL_DIR are
skipped.) Nothing is downloaded here. The zip contains the add-on package from
``blender_addon/`` (sources only), ``blender_manifest.toml`` with ``wheels``
filled in, and ``wheels/``: a pure-Python wheel of ``gerbs_core`` built from
this checkout (the core "vendored" the way Blender installs dependencies) plus
the wheels from WHEEL_DIR. The result is checked with Blender's own validator
(``bl_pkg/cli/blender_ext.py validate``) when ``bpy`` is importable.
"""
from __future__ import annotations

import argparse
import base64
import hashlib
import re
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ADDON = ROOT / "blender_addon"
CORE = ROOT / "gerbs_core"


def _version() -> str:
    text = (CORE / "__init__.py").read_text()
    return re.search(r'__version__ = "([^"]+)"', text).group(1)


def _sources(package: Path):
    for path in sorted(package.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix in (".py", ".toml"):
            yield path


def build_core_wheel(out_dir: Path) -> Path:
    """A pure-Python wheel of gerbs_core (PEP 427 layout, RECORD with sha256)."""
    version = _version()
    dist = f"gerbs_core-{version}"
    files: dict[str, bytes] = {}
    for path in _sources(CORE):
        if path.suffix == ".py":
            files[path.relative_to(ROOT).as_posix()] = path.read_bytes()
    files[f"{dist}.dist-info/METADATA"] = (
        f"Metadata-Version: 2.1\nName: gerbs-core\nVersion: {version}\n"
        "Summary: GERBS core (numpy + scipy), vendored for the Blender extension\n"
        "Requires-Dist: numpy\nRequires-Dist: scipy\n").encode()
    files[f"{dist}.dist-info/WHEEL"] = (
        "Wheel-Version: 1.0\nGenerator: gerbs build_extension.py\nRoot-Is-Purelib: true\n"
        "Tag: py3-none-any\n").encode()
    record = []
    for name, data in files.items():
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record.append(f"{name},sha256={digest},{len(data)}")
    record.append(f"{dist}.dist-info/RECORD,,")
    files[f"{dist}.dist-info/RECORD"] = ("\n".join(record) + "\n").encode()
    out_dir.mkdir(parents=True, exist_ok=True)
    wheel = out_dir / f"{dist}-py3-none-any.whl"
    with zipfile.ZipFile(wheel, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in files.items():
            zf.writestr(zipfile.ZipInfo(name, date_time=(2024, 1, 1, 0, 0, 0)), data)
    return wheel


def _manifest_with_wheels(wheel_names: list[str]) -> str:
    text = (ADDON / "blender_manifest.toml").read_text()
    listing = ",\n".join(f'  "./wheels/{name}"' for name in wheel_names)
    return text.rstrip() + f"\n\nwheels = [\n{listing},\n]\n"


def build(wheel_dir: Path, output: Path) -> Path:
    wheel_dir = Path(wheel_dir)
    if not wheel_dir.is_dir():
        raise SystemExit(f"error: wheel directory {wheel_dir} does not exist")
    extra = sorted(p for p in wheel_dir.glob("*.whl") if not p.name.startswith("numpy-"))
    skipped = sorted(p.name for p in wheel_dir.glob("numpy-*.whl"))
    if skipped:
        print(f"skipping {skipped}: numpy ships with Blender", file=sys.stderr)
    if not any(p.name.startswith("scipy-") for p in extra):
        print(f"warning: no scipy wheel in {wheel_dir}; the extension will only work where "
              "scipy is already importable", file=sys.stderr)
    core_wheel = build_core_wheel(output.parent / "_wheels_build")
    wheels = [core_wheel] + extra
    output.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(output, "w", zipfile.ZIP_DEFLATED) as zf:
        for path in _sources(ADDON):
            if path.name == "blender_manifest.toml":
                continue
            zf.write(path, path.relative_to(ADDON).as_posix())
        zf.writestr("blender_manifest.toml", _manifest_with_wheels([w.name for w in wheels]))
        for wheel in wheels:
            zf.write(wheel, f"wheels/{wheel.name}")
    core_wheel.unlink()
    return output


def validate(zip_path: Path) -> None:
    """Run Blender's extension validator on the zip (needs the bpy module's scripts)."""
    try:
        import importlib.util
        spec = importlib.util.find_spec("bpy")
    except ImportError:
        spec = None
    if spec is None:
        print("bpy not importable: skipping Blender's validator", file=sys.stderr)
        return
    bpy_dir = Path(spec.origin).parent
    cli = next(bpy_dir.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    out = subprocess.run([sys.executable, str(cli), "validate", str(zip_path)],
                         capture_output=True, text=True)
    print(out.stdout.strip() or out.stderr.strip())
    if out.returncode != 0 or "error" in out.stdout.lower():
        raise SystemExit(f"Blender's validator rejected {zip_path}:\n{out.stdout}{out.stderr}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("wheel_dir", type=Path, help="directory with scipy (and other) wheels")
    parser.add_argument("-o", "--output", type=Path,
                        default=ROOT / "dist" / f"gerbs_blending_surface-{_version()}.zip")
    parser.add_argument("--no-validate", action="store_true")
    args = parser.parse_args(argv)
    zip_path = build(args.wheel_dir, args.output)
    if not args.no_validate:
        validate(zip_path)
    print(f"wrote {zip_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
