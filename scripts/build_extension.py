#!/usr/bin/env python
"""Build the Blender extension zips (Blender 4.2 LTS and later): one per platform.

    # once, with access to the package index: fill the wheel cache
    .venv/bin/python scripts/build_extension.py fetch
    # offline, from the cache: one zip per platform into dist/
    .venv/bin/python scripts/build_extension.py build
    # offline, the zip for this machine's platform only
    .venv/bin/python scripts/build_extension.py build --platform current

``fetch`` downloads the scipy wheels exactly as published (``pip download
--only-binary=:all: --no-deps --platform ... --python-version ...``) for every
platform Blender ships (:data:`PLATFORMS`) and for the Python of every Blender
from 4.2 on (:data:`PYTHONS`: 3.11 for 4.2 to 5.0, 3.13 for 5.1+) into the
wheel cache (``.cache/wheels`` by default). numpy is not shipped: every
Blender bundles one that satisfies scipy's requirement (checked here).

``build`` downloads nothing. It stages the add-on (``blender_addon/``), the core
(``gerbs_core/``, copied in as the add-on's subpackage ``gerbs_core``, so the
extension carries it as its own Python code, see ``blender_addon/core.py``),
the cached wheels and a ``blender_manifest.toml`` listing ``platforms`` and
``wheels``, then runs Blender's own builder (``blender_ext.py build
--split-platforms`` from the ``bpy`` module) which writes one zip per platform
with only that platform's wheels, and finally Blender's validator on each zip.
A zip larger than :data:`MAX_ZIP_MB` is refused.
"""
from __future__ import annotations

import argparse
import importlib.util
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ADDON = ROOT / "blender_addon"
CORE = ROOT / "gerbs_core"
CACHE = ROOT / ".cache" / "wheels"
DIST = ROOT / "dist"

SCIPY = "scipy==1.17.1"
# Blender platform -> the newest platform tag its Blender accepts; pip also takes
# older compatible tags (manylinux_2_17 for 2_28, macOS 10.14 for 11.0). Blender
# 4.2+ needs glibc 2.28 and macOS 11.2; scipy's arm64 build for macOS 12 is the
# oldest it publishes, its macOS 14 (Accelerate) builds are not taken.
PLATFORMS = {
    "windows-x64": "win_amd64",
    "macos-arm64": "macosx_12_0_arm64",
    "macos-x64": "macosx_11_0_x86_64",
    "linux-x64": "manylinux_2_28_x86_64",
}
PYTHONS = ("3.11", "3.13")  # Blender 4.2 .. 5.0: CPython 3.11; Blender 5.1+: 3.13
BUNDLED_NUMPY = "1.26.4"  # the oldest numpy a supported Blender bundles (4.2 LTS)
MAX_ZIP_MB = 200  # well under the extensions platform's upload limit (300 MB)
_WHEEL = re.compile(r"^(?P<name>[^-]+)-(?P<version>[^-]+)-(?P<python>[^-]+)-(?P<abi>[^-]+)-"
                    r"(?P<platform>[^-]+)\.whl$")


def wheel_tags(filename: str) -> dict:
    """The name, version and tags of a wheel file name (PEP 427), e.g. ``python="cp311"``."""
    match = _WHEEL.match(Path(filename).name)
    if match is None:
        raise ValueError(f"not a wheel file name: {filename}")
    return match.groupdict()


def _blender_cli() -> Path:
    """Blender's extension command line (``blender_ext.py``) inside the bpy module."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise SystemExit("error: bpy is not importable: build needs Blender's own extension "
                         "builder from the bpy module (pip install bpy)")
    found = sorted(Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        raise SystemExit(f"error: no bl_pkg/cli/blender_ext.py under {Path(spec.origin).parent}")
    return found[-1]


def _blender_module():
    """blender_ext.py loaded as a module (it is plain Python: no bpy needed)."""
    module = sys.modules.get("_blender_ext")
    if module is None:
        spec = importlib.util.spec_from_file_location("_blender_ext", _blender_cli())
        module = importlib.util.module_from_spec(spec)
        sys.modules["_blender_ext"] = module
        spec.loader.exec_module(module)
    return module


def blender_platforms(wheel_name: str) -> list[str]:
    """The Blender platforms a wheel installs on, by Blender's own rule (blender_ext.py)."""
    out = []
    for tag in wheel_tags(wheel_name)["platform"].split("."):
        out += [p for p in _blender_module().blender_platforms_from_wheel_platform(tag)
                if p not in out]
    return out


# --- fetch (needs the package index) ------------------------------------------------

def fetch(cache: Path, platforms=tuple(PLATFORMS), pythons=PYTHONS) -> list[Path]:
    """Download the scipy wheel of every (platform, Python) into `cache`; returns them."""
    cache.mkdir(parents=True, exist_ok=True)
    for name in platforms:
        for python in pythons:
            abi = "cp" + python.replace(".", "")
            cmd = [sys.executable, "-m", "pip", "download", SCIPY, "--only-binary=:all:",
                   "--no-deps", "--quiet", "--implementation", "cp", "--abi", abi,
                   "--python-version", python, "--platform", PLATFORMS[name], "-d", str(cache)]
            print(f"fetching {SCIPY} for {name}, Python {python}", file=sys.stderr)
            subprocess.run(cmd, check=True)
    return select_wheels(cache, platforms, pythons)


# --- build (offline) ----------------------------------------------------------------

def select_wheels(cache: Path, platforms, pythons=PYTHONS) -> list[Path]:
    """The cached scipy wheel for every (platform, Python); SystemExit naming what is missing."""
    name, version = SCIPY.split("==")
    chosen, missing = [], []
    wheels = sorted(cache.glob(f"{name}-{version}-*.whl")) if cache.is_dir() else []
    for platform in platforms:
        for python in pythons:
            tag = "cp" + python.replace(".", "")
            fits = [w for w in wheels if wheel_tags(w.name)["python"] == tag
                    and platform in blender_platforms(w.name)]
            if fits:
                chosen.append(fits[0])
            else:
                missing.append(f"{platform}/Python {python}")
    if missing:
        raise SystemExit(f"error: no cached {SCIPY} wheel in {cache} for {', '.join(missing)}: "
                         f"run `scripts/build_extension.py fetch` once with network access")
    return chosen


def _check_numpy(wheel: Path) -> None:
    """scipy must accept the numpy that Blender bundles (numpy is not shipped)."""
    with zipfile.ZipFile(wheel) as zf:
        meta = next(n for n in zf.namelist() if n.endswith(".dist-info/METADATA"))
        text = zf.read(meta).decode()
    need = re.search(r"^Requires-Dist: numpy\s*([^;\n]*)$", text, re.M)
    low = re.search(r">=\s*([\d.]+)", need.group(1)) if need else None
    version = lambda v: tuple(int(x) for x in v.split("."))  # noqa: E731
    if low and version(low.group(1)) > version(BUNDLED_NUMPY):
        raise SystemExit(f"error: {wheel.name} needs numpy {need.group(1)} but Blender 4.2 "
                         f"bundles numpy {BUNDLED_NUMPY}: ship a numpy wheel or an older scipy")


def _manifest(platforms, wheels) -> str:
    text = (ADDON / "blender_manifest.toml").read_text()
    listing = "".join(f'  "./wheels/{w.name}",\n' for w in wheels)
    names = ", ".join(f'"{p}"' for p in platforms)
    return text.rstrip() + f"\n\nplatforms = [{names}]\n\nwheels = [\n{listing}]\n"


def _copy_sources(src: Path, dst: Path) -> None:
    shutil.copytree(src, dst, dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "blender_manifest.toml",
                                                  "README.md"))


def stage(directory: Path, platforms, wheels) -> Path:
    """Lay out the extension's source tree (what Blender's builder packs) in `directory`."""
    _copy_sources(ADDON, directory)
    _copy_sources(CORE, directory / "gerbs_core")  # the core as the add-on's own subpackage
    (directory / "wheels").mkdir()
    for wheel in wheels:
        shutil.copy2(wheel, directory / "wheels" / wheel.name)  # unmodified, as published
    (directory / "blender_manifest.toml").write_text(_manifest(platforms, wheels))
    return directory


def _blender_ext(*args) -> str:
    out = subprocess.run([sys.executable, str(_blender_cli()), *args],
                         capture_output=True, text=True)
    if out.returncode != 0 or "error" in out.stdout.lower():
        raise SystemExit(f"error: Blender's extension tool failed ({' '.join(args[:1])}):\n"
                         f"{out.stdout}{out.stderr}")
    return out.stdout


def validate(zip_path: Path) -> str:
    """Blender's own validation of an extension zip (manifest, layout, wheels)."""
    return _blender_ext("validate", str(zip_path))


def build(cache: Path = CACHE, out_dir: Path = DIST, platforms=tuple(PLATFORMS)) -> list[Path]:
    """One zip per platform into `out_dir`, validated; returns the zip paths."""
    wheels = select_wheels(cache, platforms)
    for wheel in wheels:
        _check_numpy(wheel)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="gerbs_ext_") as tmp:
        source = stage(Path(tmp) / "src", platforms, wheels)
        _blender_ext("build", "--source-dir", str(source), "--output-dir", str(out_dir),
                     "--split-platforms")
    manifest_id = re.search(r'^id = "([^"]+)"', _manifest(platforms, []), re.M).group(1)
    zips = []
    for platform in platforms:
        found = sorted(out_dir.glob(f"{manifest_id}-*-{platform.replace('-', '_')}.zip"))
        if not found:
            raise SystemExit(f"error: Blender's builder wrote no zip for {platform} in {out_dir}")
        path = found[-1]
        size_mb = path.stat().st_size / 2 ** 20
        if size_mb > MAX_ZIP_MB:
            raise SystemExit(f"error: {path.name} is {size_mb:.1f} MB, over {MAX_ZIP_MB} MB")
        validate(path)
        zips.append(path)
    return zips


def current_platform() -> str:
    """This machine's Blender platform name (e.g. "linux-x64"), by Blender's rule."""
    return _blender_module().platform_from_this_system()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    f = sub.add_parser("fetch", help="download the scipy wheels into the cache (network)")
    b = sub.add_parser("build", help="build the zips from the cache (offline)")
    for p in (f, b):
        p.add_argument("--cache", type=Path, default=CACHE, help=f"wheel cache (default {CACHE})")
        p.add_argument("--platform", action="append", choices=[*PLATFORMS, "current"],
                       help="only this platform (repeatable; default: all)")
    b.add_argument("-o", "--output-dir", type=Path, default=DIST)
    args = parser.parse_args(argv)
    platforms = args.platform or list(PLATFORMS)
    platforms = [current_platform() if p == "current" else p for p in platforms]
    unknown = [p for p in platforms if p not in PLATFORMS]
    if unknown:
        raise SystemExit(f"error: no wheels are defined for platform {unknown[0]}")
    if args.command == "fetch":
        wheels = fetch(args.cache, platforms)
        print(f"{len(wheels)} scipy wheels in {args.cache}", file=sys.stderr)
    else:
        for path in build(args.cache, args.output_dir, platforms):
            print(f"wrote {path} ({path.stat().st_size / 2 ** 20:.1f} MB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
