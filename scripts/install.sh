#!/usr/bin/env bash
# Install everything the main job and the whole test suite need (idempotent):
#   .venv           bpy 5.0.1 (the newest supported Blender, pins numpy<2), the core, pytest
#   .venvs/bpy42    bpy 4.2.0 (Blender 4.2 LTS, the oldest supported) and
#   .venvs/bpy45    bpy 4.5.15 (4.5 LTS): tests/blender/test_versions.py runs the README
#                   snippet and a compat subset in their interpreters
#   .cache/wheels   the scipy wheels every extension zip carries (all platforms, Python
#                   3.11 and 3.13), fetched from the package index here, so
#                   tests/blender/test_extension.py builds the zips offline
# Used by the README's first command and by .ci/run.
# --main-only: .venv alone (the main job, the add-on, the core and most of the tests; about
# 1.5 GB): no older bpy, no extension wheels (their tests then fail, saying how to fill them).
# Disk: about 4 GB in all (each bpy wheel is ~0.4 GB to download and 1.1-1.5 GB installed).
# pip keeps no cache copy of the wheels, and identical files inside a venv (bpy 4.2 ships
# its shared libraries three times under their version aliases) become hard links.
set -euo pipefail
case "${1:-}" in
    ""|--main-only) ;;
    *) echo "scripts/install.sh: unknown option '$1' (the only one is --main-only)" >&2; exit 2 ;;
esac
cd "$(dirname "$0")/.."
export PIP_NO_CACHE_DIR=1
# Refuse clearly, before pip fails mid-download, when the disk cannot hold one more bpy.
need_disk() {  # $1 = MB needed, $2 = what for
    local avail
    avail=$(df -Pm . | awk 'NR == 2 {print $4}')
    if [ "$avail" -lt "$1" ]; then
        echo "scripts/install.sh: installing $2 needs about $1 MB of free disk here; $avail MB are free" >&2
        exit 1
    fi
}
compact() {  # $1 = venv folder: identical files become hard links (util-linux hardlink)
    if command -v hardlink > /dev/null; then
        hardlink -q "$1" > /dev/null
    fi
}
if [ ! -x .venv/bin/python ]; then
    python3.11 -m venv .venv
fi
[ -d .venv/lib/python3.11/site-packages/bpy ] || need_disk 2000 "bpy 5.0.1 in .venv"
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -e ".[blender,test]"
compact .venv
if [ "${1:-}" = "--main-only" ]; then
    exit 0
fi
for spec in "bpy42 bpy==4.2.0" "bpy45 bpy==4.5.15"; do
    set -- $spec
    if [ ! -x ".venvs/$1/bin/python" ]; then
        python3.11 -m venv ".venvs/$1"
    fi
    [ -d ".venvs/$1/lib/python3.11/site-packages/bpy" ] || need_disk 2000 "$2 in .venvs/$1"
    ".venvs/$1/bin/python" -m pip install --quiet "$2" "numpy<2" "scipy==1.17.1"
    compact ".venvs/$1"
done
.venv/bin/python scripts/build_extension.py fetch
